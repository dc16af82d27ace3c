// motorlab ui: the page. Forms come from /api/schema (the CLI's own parsers); answers from the CLI via the API.
"use strict";

const state = { schema: null, motors: [], files: [], lastResult: null, lastExperiment: null, session: null };
const $ = (id) => document.getElementById(id);

function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") node.className = v; else if (k === "text") node.textContent = v; else node.setAttribute(k, v);
  }
  for (const c of children) node.append(c);
  return node;
}

function fmt(x, digits = 6) {
  if (x === null || x === undefined) return "?";
  if (typeof x !== "number") return String(x);
  return Number(x.toPrecision(digits)).toString();
}

async function postForm(url, form) {
  const response = await fetch(url, { method: "POST", body: form });
  const text = await response.text();
  let body;
  try { body = JSON.parse(text); } catch (e) { body = { error: text.slice(0, 300) || response.statusText }; }
  if (!response.ok) throw new Error(body.error || response.statusText);
  return body;
}

// ---- forms from the schema -------------------------------------------------------------------------
function fieldInput(f, prefix) {
  const id = `${prefix}-${f.name}`;
  let input;
  if (f.kind === "flag") {
    input = el("input", { type: "checkbox", id, name: f.name, value: "true" });
  } else if (f.kind === "choice") {
    input = el("select", { id, name: f.name });
    if ((f.default === null || f.default === undefined) && !f.required) input.append(el("option", { value: "", text: "(default)" }));
    for (const c of f.choices) {
      const opt = el("option", { value: String(c), text: String(c) });
      if (String(c) === String(f.default)) opt.selected = true;
      input.append(opt);
    }
  } else if (f.kind === "file") {
    input = el("input", { type: "file", id, name: f.name });
  } else {
    input = el("input", { type: "text", id, name: f.name, placeholder: f.default === null ? "" : String(f.default) });
  }
  const label = el("label", { for: id }, f.option || f.name);
  if (f.unit) label.append(el("span", { class: "unit", text: ` [${f.unit}]` }));
  if (f.required) label.append(el("span", { class: "unit", text: " (required)" }));
  const help = f.help + (f.default !== null && f.default !== undefined && f.kind !== "flag" ? ` — default ${f.default}` : "");
  return el("div", { class: "field" }, label, input, el("small", { text: help }));
}

function buildForm(form, fields, prefix) {
  form.replaceChildren();
  for (const f of fields) {
    if (f.positional && f.kind === "file") continue;  // the dropped files
    form.append(fieldInput(f, prefix));
  }
}

function formValues(form, data) {
  for (const input of form.querySelectorAll("input, select")) {
    if (input.type === "checkbox") { if (input.checked) data.append(input.name, "true"); }
    else if (input.type === "file") { for (const file of input.files) data.append(input.name, file); }
    else if (input.value.trim() !== "") data.append(input.name, input.value.trim());
  }
  return data;
}

function showExperiment() {
  const name = $("experiment").value;
  const spec = state.schema.analyze[name];
  $("experiment-help").textContent = spec.description;
  buildForm($("options"), spec.fields, "opt");
  applyMotor();
}

function applyMotor() {
  const motor = state.motors.find((m) => m.key === $("motor").value);
  if (!motor) return;
  for (const prefix of ["opt", "tune"]) {
    const cpr = $(`${prefix}-cpr`); if (cpr) cpr.value = String(motor.cpr);
    // Only an option that IS the gearbox ratio: spindown's --ratio is the flywheel's step-up, not this.
    const gear = $(`${prefix}-gear-ratio`); if (gear) gear.value = String(motor.gear_ratio);
  }
}

// ---- analyze ---------------------------------------------------------------------------------------
async function onFiles(files) {
  state.files = Array.from(files);
  $("detected").replaceChildren();
  if (!state.files.length) return;
  const data = new FormData();
  for (const f of state.files) data.append("file", f);
  $("status").textContent = "reading…";
  try {
    const found = await postForm("api/detect", data);
    for (const item of found) {
      const line = el("div", { class: "detected-file" }, el("strong", { text: item.file }), " ");
      if (item.error) line.append(el("span", { class: "error", text: item.error }));
      else line.append("format ", el("code", { text: item.format }), ", proposed experiment ", el("code", { text: item.experiment }));
      $("detected").append(line);
    }
    const first = found.find((item) => !item.error);
    if (first) {
      $("experiment").value = first.experiment;
      showExperiment();
      plotRaw(first);
    }
    $("status").textContent = "";
  } catch (e) { $("status").textContent = ""; $("error").textContent = e.message; }
}

function plotRaw(item) {
  if (!window.Plotly) return;
  const traces = item.signals.map((s, k) => ({ x: item.time, y: s.y, name: `${s.name} [${s.unit}]`, yaxis: k ? `y${k + 1}` : "y", mode: "lines" }));
  const n = traces.length;
  const layout = { title: { text: `${item.file}: raw data` }, height: 140 + 130 * n, margin: { t: 40, r: 20 }, grid: { rows: n, columns: 1, pattern: "independent" }, showlegend: true };
  traces.forEach((t, k) => { t.xaxis = k ? `x${k + 1}` : "x"; layout[`xaxis${k ? k + 1 : ""}`] = { matches: "x", title: { text: k === n - 1 ? "time [s]" : "" } }; });
  Plotly.react($("raw-plot"), traces, layout, { responsive: true, displaylogo: false });
}

async function runAnalysis() {
  const experiment = $("experiment").value;
  $("error").textContent = ""; $("result").hidden = true;
  if (!state.files.length) { $("error").textContent = "drop a log first"; return; }
  const make = () => { const d = new FormData(); for (const f of state.files) d.append("file", f); return formValues($("options"), d); };
  $("status").textContent = "running…";
  try {
    const [result, panels] = await Promise.all([
      postForm(`api/analyze/${encodeURIComponent(experiment)}`, make()),
      postForm(`api/panels/${encodeURIComponent(experiment)}`, make()).catch(() => []),
    ]);
    state.lastResult = result; state.lastExperiment = experiment;
    showResult(Array.isArray(result) ? result[0] : result);
    plotPanels(panels);
    $("status").textContent = "done";
  } catch (e) { $("status").textContent = ""; $("error").textContent = e.message; }
}

function showResult(r) {
  const body = $("results").tBodies[0];
  body.replaceChildren();
  const shaft = r.details && r.details.shaft ? r.details.shaft : "";
  for (const [name, p] of Object.entries(r.parameters)) {
    const value = p.determined === false ? "not determined" : fmt(p.value);
    body.append(el("tr", { "data-name": name }, el("td", { text: name }), el("td", { class: "num value", text: value }),
      el("td", { class: "num stderr", text: fmt(p.stderr, 2) }), el("td", { text: p.unit }),
      el("td", { text: typeof shaft === "string" ? shaft : JSON.stringify(shaft) }), el("td", { text: p.note || "" })));
  }
  $("warnings").replaceChildren(...r.warnings.map((w) => el("li", { text: w })));
  const diag = $("diagnostics").tBodies[0];
  diag.replaceChildren(
    el("tr", {}, el("th", { text: "RMS residual" }), el("td", { text: `${fmt(r.fit.rmse, 4)} ${r.fit.rmse_unit}` })),
    el("tr", {}, el("th", { text: "R²" }), el("td", { text: fmt(r.fit.r2, 6) })),
    el("tr", {}, el("th", { text: "points" }), el("td", { text: String(r.fit.n_points) })));
  if (r.fit.correlation) {
    const { names, matrix } = r.fit.correlation;
    const pairs = [];
    names.forEach((a, i) => names.forEach((b, j) => { if (j > i && Math.abs(matrix[i][j]) >= 0.5) pairs.push(`${a}–${b}: ${fmt(matrix[i][j], 3)}`); }));
    diag.append(el("tr", {}, el("th", { text: "correlations ≥ 0.5" }), el("td", { text: pairs.join(", ") || "none" })));
  }
  $("result").hidden = false;
}

function plotPanels(panels) {
  const host = $("fit-plot");
  host.replaceChildren();
  if (!window.Plotly) return;
  for (const p of panels) {
    const div = el("div", { class: "plot" });
    host.append(div);
    const traces = [];
    if (p.data) traces.push({ x: p.data.x, y: p.data.y, name: p.data.label, mode: "markers", marker: { size: 4 } });
    if (p.model) traces.push({ x: p.model.x, y: p.model.y, name: p.model.label, mode: "lines" });
    for (const s of p.extra) traces.push({ x: s.x, y: s.y, name: s.label, mode: s.kind === "data" ? "markers" : "lines" });
    const layout = { title: { text: p.title }, height: 420, margin: { t: 40, r: 20 }, xaxis: { title: { text: p.x_label } }, yaxis: { title: { text: p.y_label } } };
    if (p.same_x && p.data && p.model) {
      const res = p.data.y.map((y, k) => (y === null || p.model.y[k] === null ? null : y - p.model.y[k]));
      traces.push({ x: p.data.x, y: res, name: "residual", mode: "markers", marker: { size: 3 }, xaxis: "x2", yaxis: "y2" });
      layout.height = 560;
      layout.xaxis = { anchor: "y", showticklabels: false };
      layout.yaxis.domain = [0.32, 1];
      layout.xaxis2 = { matches: "x", anchor: "y2", title: { text: p.x_label } };
      layout.yaxis2 = { domain: [0, 0.26], title: { text: "residual" }, anchor: "x2" };
    }
    Plotly.react(div, traces, layout, { responsive: true, displaylogo: false });
  }
}

function download(name, text, type) {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = el("a", { href: url, download: name });
  document.body.append(a); a.click(); a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

// ---- session ---------------------------------------------------------------------------------------
async function runSession() {
  const files = $("session-files").files;
  $("session-error").textContent = ""; $("session-result").hidden = true;
  if (!files.length) { $("session-error").textContent = "choose the session file and its logs (or a zip)"; return; }
  const data = new FormData();
  for (const f of files) data.append("file", f, f.webkitRelativePath || f.name);
  $("session-progress").hidden = false;
  const start = Date.now();
  const tick = setInterval(() => { $("session-status").textContent = `running the analyses… ${Math.round((Date.now() - start) / 1000)} s`; }, 500);
  try {
    const body = await postForm("api/characterize", data);
    state.session = body;
    showSession(body);
    $("session-status").textContent = body.message ? `done, with failures: ${body.message}` : "done";
  } catch (e) { $("session-status").textContent = ""; $("session-error").textContent = e.message; }
  finally { clearInterval(tick); $("session-progress").hidden = true; }
}

function showSession(body) {
  const r = body.results;
  $("session-title").textContent = r.session.title || "";
  const names = [];
  for (const unit of Object.values(r.units)) for (const n of Object.keys(unit.parameters || {})) if (!names.includes(n)) names.push(n);
  $("session-table").tHead.replaceChildren(el("tr", {}, el("th", { text: "unit" }), el("th", { text: "status" }), ...names.map((n) => el("th", { text: n }))));
  const rows = Object.values(r.units).map((unit) => el("tr", {}, el("td", { text: unit.label }), el("td", { text: unit.status }),
    ...names.map((n) => { const p = (unit.parameters || {})[n]; return el("td", { class: "num", text: p ? `${fmt(p.value, 4)} ± ${fmt(p.stderr, 2)} ${p.unit}` : "" }); })));
  $("session-table").tBodies[0].replaceChildren(...rows);
  const fleet = r.fleet && r.fleet.parameters ? r.fleet.parameters : {};
  $("fleet-table").tBodies[0].replaceChildren(...Object.entries(fleet).map(([n, f]) => {
    const flagged = Object.entries(f.z || {}).filter(([, z]) => Math.abs(z) > r.fleet.threshold).map(([u, z]) => `${u} (z = ${fmt(z, 3)})`);
    return el("tr", {}, el("td", { text: n }), el("td", { text: f.unit }), el("td", { class: "num", text: String(f.n) }),
      el("td", { class: "num", text: fmt(f.mean, 4) }), el("td", { class: "num", text: fmt(f.std, 2) }), el("td", { text: flagged.join(", ") || "none" }));
  }));
  $("report").srcdoc = body.report_html;
  $("session-result").hidden = false;
}

// ---- gains -----------------------------------------------------------------------------------------
function tuneForm() {
  const data = formValues($("tune-options"), new FormData());
  if (state.lastResult && !data.has("params") && !data.has("kv")) {
    data.append("params", new Blob([JSON.stringify(state.lastResult)], { type: "application/json" }), `${state.lastExperiment}.json`);
  }
  return data;
}

async function runTune() {
  $("tune-error").textContent = ""; $("tune-result").hidden = true;
  $("tune-status").textContent = "designing…";
  try {
    const languages = ["java", "kotlin", "python"];
    const withEmit = (lang) => { const d = tuneForm(); d.append("emit", lang); return d; };
    // One call per language the CLI can emit; a target refuses some (FTC OpModes: no Python): those are left out.
    const settled = await Promise.allSettled(languages.map((lang) => postForm("api/tune", withEmit(lang))));
    const made = settled.map((s, k) => [languages[k], s]).filter(([, s]) => s.status === "fulfilled");
    if (!made.length) throw settled[0].reason;
    showTune(made[0][1].value, made.map(([lang, s]) => [lang, s.value.snippet]));
    const figure = await fetch("api/tune/figure", { method: "POST", body: tuneForm() });
    if (figure.ok) $("step-figure").src = URL.createObjectURL(await figure.blob());
    $("tune-status").textContent = "done";
  } catch (e) { $("tune-status").textContent = ""; $("tune-error").textContent = e.message; }
}

function showTune(d, snippets) {
  const u = d.units || {};
  const rows = [];
  for (const [k, v] of Object.entries(d.gains)) rows.push(el("tr", {}, el("th", { text: k }), el("td", { class: "num", text: fmt(v) }), el("td", { text: u[k] || "" })));
  for (const [k, v] of Object.entries(d.feedforward)) rows.push(el("tr", {}, el("th", { text: k }), el("td", { class: "num", text: fmt(v) }), el("td", { text: u[k] || "" })));
  const r = d.response;
  rows.push(el("tr", {}, el("th", { text: "rise time" }), el("td", { class: "num", text: r.rise_time === null ? "not reached" : fmt(r.rise_time * 1e3, 4) }), el("td", { text: "ms" })));
  rows.push(el("tr", {}, el("th", { text: "overshoot" }), el("td", { class: "num", text: fmt(r.overshoot, 3) }), el("td", { text: "%" })));
  $("gains-table").tBodies[0].replaceChildren(...rows);
  $("tune-notes").replaceChildren(...[...d.conversion, ...d.notes, ...d.warnings].map((t) => el("li", { text: t })));
  $("snippets").replaceChildren(...snippets.map(([lang, code]) => {
    const button = el("button", { class: "copy", "data-lang": lang, text: "Copy" });
    button.addEventListener("click", async () => {
      try { await navigator.clipboard.writeText(code); button.textContent = "Copied"; }
      catch (e) { const range = document.createRange(); range.selectNodeContents(button.parentNode.nextSibling); getSelection().removeAllRanges(); getSelection().addRange(range); document.execCommand("copy"); button.textContent = "Copied"; }
    });
    return el("div", { class: "snippet" }, el("header", {}, el("span", { text: `${d.target} · ${lang}` }), button), el("pre", {}, el("code", { text: code })));
  }));
  $("tune-result").hidden = false;
}

// ---- start -----------------------------------------------------------------------------------------
async function start() {
  state.schema = await (await fetch("api/schema")).json();
  state.motors = await (await fetch("api/motors")).json();
  for (const name of Object.keys(state.schema.analyze)) $("experiment").append(el("option", { value: name, text: name }));
  for (const m of state.motors) $("motor").append(el("option", { value: m.key, text: `${m.name} (${m.cpr} counts/rev, ${m.gear_ratio}:1)` }));
  buildForm($("tune-options"), state.schema.tune.fields, "tune");
  showExperiment();
  $("experiment").addEventListener("change", showExperiment);
  $("motor").addEventListener("change", applyMotor);
  $("files").addEventListener("change", (e) => onFiles(e.target.files));
  const drop = $("drop");
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => { e.preventDefault(); drop.classList.remove("over"); onFiles(e.dataTransfer.files); });
  for (const form of document.querySelectorAll("form")) form.addEventListener("submit", (e) => e.preventDefault());
  $("run").addEventListener("click", runAnalysis);
  $("to-gains").addEventListener("click", () => { selectTab("gains"); $("gains-source").textContent = `plant: the ${state.lastExperiment} result (unless --kv/--ka or --params are given below)`; });
  $("download-json").addEventListener("click", () => download(`${state.lastExperiment}.json`, JSON.stringify(state.lastResult, null, 2), "application/json"));
  $("run-session").addEventListener("click", runSession);
  $("dl-json").addEventListener("click", () => download("results.json", JSON.stringify(state.session.results, null, 2), "application/json"));
  $("dl-csv").addEventListener("click", () => download("results.csv", state.session.csv, "text/csv"));
  $("dl-html").addEventListener("click", () => download("report.html", state.session.report_html, "text/html"));
  $("run-tune").addEventListener("click", runTune);
  for (const tab of document.querySelectorAll(".tab")) tab.addEventListener("click", () => selectTab(tab.dataset.tab));
  document.body.dataset.ready = "true";
}

function selectTab(name) {
  for (const t of document.querySelectorAll(".tab")) t.classList.toggle("active", t.dataset.tab === name);
  for (const p of document.querySelectorAll(".panel")) p.classList.toggle("active", p.id === name);
}

document.addEventListener("DOMContentLoaded", () => { start().catch((e) => { $("error").textContent = `the page could not start: ${e.message}`; }); });
