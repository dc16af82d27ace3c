// Step "Your files and the fit": files recognised on upload (format and proposal beside each file, a reader's
// refusal too), one analysis per kind of measurement, each with its own options, Run/Cancel, progress and result.
import { $, commandBox, debounce, el, uid } from "../dom.js";
import { post, run as runRequest, isAbort } from "../api.js";
import { save, settings } from "../store.js";
import { argvOf, appendValues, field, isShared } from "../fields.js";
import { EXPERIMENT_WORDS, plain } from "../words.js";
import * as plots from "../plots.js";
import { changes, leftOut, makeRecord, recordView, result as resultView, settingsUsed } from "../results.js";
import { eachRunTable, fitEachAlone, fitsEachAlone } from "../runs.js";
import { findTask } from "../tasks.js";

// Options shown at once (the others under "More options"), besides required, shared and needed ones.
const PRIMARY = { spindown: ["inertia", "disc-radius", "disc-thickness", "ratio"], feedforward: ["mechanism"], torque: ["arm"], terminal: ["inertia"] };
const controllers = new Map();  // experiment -> AbortController of its running request (not kept in the state)

export async function addFiles(t, files) {
  const form = new FormData();
  for (const f of files) form.append("file", f, f.name);
  const found = await post("api/detect", form);
  found.forEach((info, k) => {
    t.files.push({ id: `file-${Date.now().toString(36)}-${Math.random().toString(36).slice(2, 8)}`, name: files[k].name, file: files[k], info, experiment: info.experiment || "", chosen: false });
  });
  save();
}

// An experiment in words: the app's own, else the title its description gives (never its key).
function experimentWords(ctx, key) {
  return EXPERIMENT_WORDS[key] || (ctx.app.schema.analyze[key] || {}).title || key;
}

function proposalWords(ctx, info) {
  if (/^roadrunner/.test(info.format || "")) return "Road Runner feedforward fit (kS, kV, kA)";
  return experimentWords(ctx, info.experiment);
}

function fileRow(ctx, entry) {
  const t = ctx.state, info = entry.info || {};
  const id = uid("exp");
  const remove = el("button", { type: "button", class: "link", text: "remove", "aria-label": `Remove ${entry.name}`,
    onclick: () => { t.files = t.files.filter((f) => f !== entry); save(); ctx.rerender(); } });
  if (info.error && info.column) return columnQuestion(ctx, entry, remove);
  if (info.error) {
    return el("li", { class: "file refused" }, el("strong", { text: entry.name }), " ",
      el("span", { class: "error", role: "alert", text: `${plain(info.error)}. Check this file, or choose another one.` }), " ", remove);
  }
  if (info.format === "session") {
    return el("li", { class: "file" }, el("strong", { text: entry.name }), ": a session description. ",
      el("a", { href: "#/bench/session", text: `${findTask("bench").title} with it` }), " ", remove);
  }
  const select = el("select", { id, onchange: (e) => { entry.experiment = e.target.value; entry.chosen = true; save(); ctx.rerender(); } });
  for (const key of Object.keys(ctx.app.schema.analyze)) {
    const words = key === info.experiment ? proposalWords(ctx, info) : experimentWords(ctx, key);
    select.append(el("option", { value: key, text: words, selected: key === entry.experiment }));
  }
  const differs = entry.chosen && info.experiment && entry.experiment !== info.experiment;
  return el("li", { class: "file", "data-file": entry.name },
    el("strong", { text: entry.name }), el("span", { class: "format", text: ` ${info.format_words || info.format}` }),
    el("div", { class: "proposal" }, el("span", { text: "Proposed: " }), el("span", { class: "proposed", text: proposalWords(ctx, info) })),
    el("div", { class: "field inline" }, el("label", { for: id, text: "What this file measures" }), select),
    differs ? el("p", { class: "small" }, `This file looks like ${proposalWords(ctx, info)}. `,
      el("button", { type: "button", class: "link", text: "Use that", onclick: () => { entry.experiment = info.experiment; entry.chosen = false; save(); ctx.rerender(); } })) : null,
    remove);
}

// "Which quantity is the column 'Load'?": the answer becomes a column rule ("Load=torque [oz*in]") the file
// is read again with, and that every fit of the file passes on.
function columnQuestion(ctx, entry, remove) {
  const { column, quantities } = entry.info;
  const [qid, uidUnit] = [uid("column"), uid("unit")];
  const quantity = el("select", { id: qid }, el("option", { value: "", text: "choose…" }),
    quantities.map((q) => el("option", { value: q, text: q === "skip" ? "nothing to read (leave it out)" : q.replace(/_/g, " ") })));
  const unit = el("input", { type: "text", id: uidUnit, placeholder: "e.g. mA, oz*in, rpm", autocomplete: "off" });
  const status = el("span", { role: "status" });
  const apply = el("button", { type: "button", class: "primary", text: "Read the file again", onclick: async () => {
    if (!quantity.value) { status.textContent = "choose what the column holds first"; return; }
    entry.columns = [...(entry.columns || []), `${column}=${quantity.value}${unit.value.trim() ? ` [${unit.value.trim()}]` : ""}`];
    status.textContent = "reading…";
    try { await redetect(entry); save(); ctx.rerender(); } catch (e) { status.textContent = e.message; }
  } });
  return el("li", { class: "file refused", "data-file": entry.name }, el("strong", { text: entry.name }),
    el("p", { class: "error", role: "alert", text: `motorlab does not know what the column “${column}” holds.` }),
    el("div", { class: "options" },
      el("div", { class: "field" }, el("label", { for: qid, text: `Which quantity is the column “${column}”?` }), quantity),
      el("div", { class: "field" }, el("label", { for: uidUnit, text: "Its unit, if the header does not say" }), unit)),
    el("div", { class: "actions" }, apply, status, remove));
}

async function redetect(entry) {
  const form = new FormData();
  form.append("file", entry.file, entry.name);
  for (const rule of entry.columns || []) form.append("column", rule);
  const [info] = await post("api/detect", form);
  entry.info = info;
  entry.experiment = entry.chosen ? entry.experiment : info.experiment || "";
}

const columnRules = (files) => files.flatMap((f) => f.columns || []);

// One fit per file, except an FTC log split over several files (testFile.txt + testFile2.txt), which is one run.
export function groups(t) {
  const out = new Map();
  for (const f of t.files) {
    if (!f.info || f.info.error || !f.experiment) continue;
    // runs fitted together (a motor's stall runs: motorlab analyze stall A.csv B.csv), as the upload proposed
    const key = f.info.group && f.experiment === f.info.experiment ? f.info.group
      : f.info.format === "ftc-log" ? f.experiment : `${f.experiment}:${f.id}`;
    if (!out.has(key)) out.set(key, []);
    out.get(key).push(f);
  }
  return out;
}

// The units a group's files carry (SysId's units and unitsPerRotation), when every file carries them.
export const ownUnits = (files) => (files.length && files.every((f) => f.info && f.info.own_units) ? files[0].info.own_units : null);

// The options of a fit of these files: a file that carries its own units is fitted in them, so the
// mechanism's counts per revolution, wheel radius and gear ratio (typed for something else) never apply to it.
export function fitFields(ctx, exp, files) {
  const all = ctx.app.schema.analyze[exp].fields;
  return ownUnits(files) ? all.filter((f) => !isShared(f.name)) : all;
}

// What a result was made with that differs from what is in force now ([] when it agrees): one sentence each.
export function staleness(ctx, run) {
  const record = run && run.record;
  if (!record || !ctx.app.schema.analyze[record.experiment]) return [];
  const fields = ctx.app.schema.analyze[record.experiment].fields.filter((f) => (record.fields || []).includes(f.name));
  return changes(record, fields, settingsUsed(fields, ctx.state.options[record.experiment] || {}, settings(), isShared));
}

function optionsForm(ctx, exp, files) {
  const t = ctx.state;
  const values = (t.options[exp] = t.options[exp] || {});
  const fields = fitFields(ctx, exp, files).filter((f) => !f.positional && f.kind !== "file");
  const needs = new Set(files.flatMap((f) => (f.info && f.info.needs) || []));
  const primary = fields.filter((f) => f.required || isShared(f.name) || needs.has(f.name) || (PRIMARY[exp] || []).includes(f.name));
  const more = fields.filter((f) => !primary.includes(f));
  const note = (f) => (f.name === "cpr" && needs.has("cpr") ? "needed: this log counts encoder ticks" : "");
  const own = ownUnits(files);
  // a setting changed after a fit: its result says so at once (the view drawn again, the field kept as typed)
  const redraw = debounce(() => { if (Object.values(t.runs).some((r) => r.result)) ctx.rerender(); }, 400);
  const box = el("div", { class: "options" }, primary.map((f) => field(f, values, redraw, { note: note(f) })),
    own ? el("p", { class: "small own-units", text: `Fitted in the file's own units (${own.units}${own.per_rotation ? `, ${own.per_rotation} per rotation` : ""}): no counts per revolution or wheel radius applies to it.` }) : null);
  return [fields, values, box, more.length ? el("details", { class: "more" }, el("summary", { text: "More options for this fit" }),
    el("div", { class: "options" }, more.map((f) => field(f, values, redraw)))) : null];
}

function analyzeCommand(exp, files, fields, values) {
  return ["analyze", exp, ...files.map((f) => f.name), ...columnRules(files).map((r) => `--column=${r}`), ...argvOf(fields, values)];
}

async function runGroup(ctx, key, files) {
  const t = ctx.state, exp = files[0].experiment;
  const [fields, values] = [fitFields(ctx, exp, files), t.options[exp] || {}];
  const names = files.map((f) => f.name);
  const form = new FormData();
  for (const f of files) form.append("file", f.excluded && f.excluded.length ? f.trimmed || f.file : f.file, f.name);
  for (const rule of columnRules(files)) form.append("column", rule);
  appendValues(form, fields, values);
  // the record of how the result is made, taken at the click (a setting typed while it runs is not in it)
  const recording = makeRecord({ experiment: exp, files, fields, settings: settingsUsed(fields, values, settings(), isShared),
    ownUnits: ownUnits(files), columns: columnRules(files), command: analyzeCommand(exp, files, fields, values) });
  const previous = t.runs[key] && t.runs[key].result ? t.runs[key] : null;  // a finished result is kept until a new one replaces it
  const run = (t.runs[key] = { ...(previous || {}), experiment: exp, files: previous ? previous.files : names, status: "running", started: Date.now(), error: "" });
  const controller = new AbortController();
  controllers.set(key, controller);
  ctx.rerender();
  try {
    const answer = await runRequest(`api/analyze/${encodeURIComponent(exp)}/plots`, form, { signal: controller.signal, onProgress: (p) => progress(key, p) });
    Object.assign(run, { status: "done", result: answer.result, panels: answer.panels, record: await recording, files: names, finished: Date.now(),
      excluded: files.reduce((n, f) => n + (f.excluded || []).length, 0), id: `${key}@${Date.now().toString(36)}` });
    if (t.gains.use[key] === undefined) t.gains.use[key] = true;
    if (fitsEachAlone(files)) {  // each run's own answer beside the joint one (runs.js)
      run.each = []; ctx.rerender();
      run.each = await fitEachAlone(exp, files, fields, values, columnRules(files), { signal: controller.signal }).catch(() => null);
    }
  } catch (e) {
    // a mistake (a wrong option, a cancel) never erases the result before it: it stays, with the error above it
    Object.assign(run, { status: isAbort(e) ? "stopped" : "failed", error: isAbort(e) ? "" : e.message });
    if (!previous) { delete run.result; delete run.panels; }
  } finally {
    controllers.delete(key);
    save();
    ctx.rerender();
  }
}

function progress(key, p) {
  const bar = $(`[data-group="${key}"] progress`), text = $(`[data-group="${key}"] .run-status`);
  if (bar && p.total) { bar.max = p.total; bar.value = p.done || 0; }
  if (text) text.textContent = plain(`${p.what || "working"}${p.total ? `: ${p.done || 0} of ${p.total} ${p.unit || ""}` : ""}${p.detail ? ` (${p.detail})` : ""}`);
}

// The plots of each result, drawn once: a redraw of the view (a result arriving, a field typed in) moves the same
// figures into the new view instead of drawing them again (two SysId results drawn again at each keystroke froze
// the page for seconds).
const drawn = new Map();  // run id -> { host, exclude }

function groupCard(ctx, key, files) {
  const t = ctx.state, run = t.runs[key], exp = files[0].experiment;
  const [fields, values, box, more] = optionsForm(ctx, exp, files);
  const running = run && run.status === "running" && controllers.has(key);
  const runButton = el("button", { type: "button", class: "primary", text: running ? "Running…" : "Run the fit", disabled: running,
    onclick: () => runGroup(ctx, key, files) });
  const cancel = el("button", { type: "button", text: "Cancel", hidden: !running, onclick: () => { const c = controllers.get(key); if (c) c.abort(); } });
  const card = el("section", { class: "card group", "data-group": key },
    el("h3", { text: /^roadrunner/.test((files[0].info || {}).format || "") ? "Road Runner feedforward fit (kS, kV, kA)" : experimentWords(ctx, exp) }),
    el("p", { class: "small", text: `From ${files.map((f) => f.name).join(", ")}` }),
    box, more, commandBox(analyzeCommand(exp, files, fields, values)),
    el("div", { class: "actions" }, runButton, cancel, running ? el("progress", { "aria-label": "Progress of the fit" }) : null,
      el("span", { class: "run-status", role: "status", text: running ? "fitting…" : run && run.status === "stopped" ? "cancelled" : "" })));
  if (run && run.status === "failed") {
    card.append(el("p", { class: "error", role: "alert", text: run.result ? `This fit failed: ${run.error} The result below is the one before, kept as it was.` : `${run.error}` }));
  }
  if (run && run.result) {
    const same = run.files.join("\n") === files.map((f) => f.name).join("\n");
    const left = files.reduce((n, f) => n + (f.excluded || []).length, 0);
    const spans = leftOut(run.result);
    const spanCount = spans ? spans.spans.length : 0;
    const leftWords = run.excluded ? ` (${run.excluded} point${run.excluded > 1 ? "s" : ""} left out)`
      : spanCount ? ` (${spanCount} time span${spanCount > 1 ? "s" : ""} left out)` : "";
    card.append(el("h4", { text: `Result from ${run.files.join(", ")}${leftWords}` }));
    const stale = staleness(ctx, run);
    if (stale.length) {
      card.append(el("div", { class: "stale", role: "alert" },
        el("p", { text: `${stale.map(sentence).join(" ").replace(/\.$/, "")}: fit again. Until then this result and its gains stay as they were made.` }),
        el("button", { type: "button", class: "primary", text: "Fit again with what you have now", onclick: () => runGroup(ctx, key, files) })));
    }
    if (left) card.append(el("p", { class: "small" }, `${left} point${left > 1 ? "s are" : " is"} left out of the fit. `,
      el("button", { type: "button", class: "link", text: "Put them back", onclick: () => { for (const f of files) f.excluded = []; save(); runGroup(ctx, key, files); } })));
    if (spans) card.append(el("p", { class: "small left-out" }, `${sentence(spans.text)} `,
      el("button", { type: "button", class: "link", text: "Put them back", onclick: () => { values.exclude = ""; save(); runGroup(ctx, key, files); } })));
    if (!same) card.append(el("p", { class: "small", text: "The files have changed since this result: run the fit again to update it." }));
    card.append(...resultView(run.result), eachRunTable(exp, run.result, run.each) || "", recordView(run.record, fields));
    const table = files.length === 1 && (files[0].info || {}).format === "csv";
    const timed = takesSpans(fields) && (run.panels || []).some((p) => (p.time || []).some((v) => v !== null));
    const how = timed ? "To leave a stretch of the log out (the wheels slipping, a glitch): pick the box or lasso tool above a plot, select its points, then fit again."
      : "To leave points out: pick the box or lasso tool above a plot, select the points, then fit again.";
    const id = run.id || `${key}@${run.finished}`;
    let kept = drawn.get(id);
    if (!kept) {
      kept = { host: el("div", { class: "plots" }), exclude: el("div", { class: "actions exclude" }) };
      drawn.set(id, kept);
      const { host, exclude } = kept;
      const command = (extra) => commandBox(analyzeCommand(exp, files, fields, { ...values, exclude: [values.exclude, extra].filter(Boolean).join(", ") }));
      plots.panels(host, run.panels, { leftOut: spans ? spans.spans : [], onSelect: (panel, indices) => {
        if (timed && panel.time) offerSpans(ctx, key, files, spanChoice(panel, indices), exclude, command);
        else if (timed) exclude.replaceChildren(el("p", { class: "small", text: "This plot's points are not samples of the log: select the stretch to leave out on a plot against time." }));
        else offerExclusion(ctx, key, files, panel, indices, exclude);
      } });
    }
    card.append(table || timed ? el("p", { class: "small", text: how }) : "", kept.exclude, kept.host);
  }
  return card;
}

const takesSpans = (fields) => fields.some((f) => f.name === "exclude");
const sentence = (text) => `${text.charAt(0).toUpperCase()}${text.slice(1)}.`;

// The time spans (in the log's own time) that the selected points cover: points closer than three sampling
// steps are one span; each span reaches half a step beyond its outer points, rounded outwards.
export function spanChoice(panel, indices) {
  const time = panel.time || [];
  const picked = indices.map((i) => time[i]).filter((v) => v !== null && v !== undefined).sort((a, b) => a - b);
  if (!picked.length) return [];
  const all = time.filter((v) => v !== null && v !== undefined).sort((a, b) => a - b);
  const steps = all.slice(1).map((v, k) => v - all[k]).filter((d) => d > 0).sort((a, b) => a - b);
  const step = steps.length ? steps[Math.floor(steps.length / 2)] : 0;
  const groups = [];
  for (const v of picked) {
    const last = groups[groups.length - 1];
    if (last && v - last[1] <= 3 * step) last[1] = v; else groups.push([v, v]);
  }
  const digits = Math.min(4, Math.max(1, Math.ceil(-Math.log10(Math.max(step, 1e-4)))));
  const f = 10 ** digits;
  return groups.map(([a, b]) => {
    const [start, end] = [Math.floor((a - step / 2) * f) / f, Math.ceil((b + step / 2) * f) / f];
    return { words: `${start.toFixed(digits)}–${end.toFixed(digits)} s`, value: `${start.toFixed(digits)}:${end.toFixed(digits)}` };
  });
}

// Points selected on a long log's plot: leave their time span(s) out and fit again (the analysis cuts the log there).
function offerSpans(ctx, key, files, spans, host, command) {
  host.replaceChildren();
  if (!spans.length) return;
  const exp = files[0].experiment;
  const values = (ctx.state.options[exp] = ctx.state.options[exp] || {});
  const more = spans.map((s) => s.value).join(", ");
  const words = spans.map((s) => s.words);
  const said = words.length > 1 ? `${words.slice(0, -1).join(", ")} and ${words[words.length - 1]}` : words[0];
  host.append(el("button", { type: "button", class: "primary", text: `Leave out ${said} and fit again`, onclick: () => {
    values.exclude = [values.exclude, more].filter(Boolean).join(", ");
    save();
    runGroup(ctx, key, files);
  } }), Object.assign(command(more), { open: true }));
}

// The data rows of a small table file (the points of its fit, one per row, when nothing was thinned).
function dataRows(lines) {
  const rows = [];
  let header = false;
  lines.forEach((line, k) => {
    const t = line.trim();
    if (!t || t.startsWith("#")) return;
    if (!header && /[A-Za-z]/.test(t.replace(/[eE][+-]?\d/g, ""))) { header = true; return; }
    header = true;
    rows.push(k);
  });
  return rows;
}

// Points selected on a fit's plot: leave their rows out of a copy of the file (the file itself is kept) and fit again.
async function offerExclusion(ctx, key, files, panel, indices, host) {
  host.replaceChildren();
  if (!indices.length) return;
  const entry = files.length === 1 ? files[0] : null;
  const current = entry && entry.excluded && entry.excluded.length && entry.trimmed ? entry.trimmed : entry && entry.file;
  const text = entry ? await current.text() : "";
  const lines = text.split(/\r?\n/);
  const rows = dataRows(lines);
  const n = panel.data ? panel.data.x.length : -1;
  if (!entry || rows.length !== n) {
    host.append(el("p", { class: "small", text: "Points can be left out of a fit of one table file whose every row is a point (an LCR, torque or terminal-speed table); this fit's points come from a longer log." }));
    return;
  }
  host.append(el("button", { type: "button", class: "primary", text: `Leave out the ${indices.length} selected point${indices.length > 1 ? "s" : ""} and fit again`, onclick: () => {
    const drop = new Set(indices.map((i) => rows[i]));
    entry.excluded = [...(entry.excluded || []), ...[...drop].map((k) => lines[k])];  // the rows left out, as they were
    entry.trimmed = new Blob([lines.filter((_, k) => !drop.has(k)).join("\n")], { type: "text/plain" });
    save();
    runGroup(ctx, key, files);
  } }));
}

function motorPicker(ctx) {
  const id = uid("motor");
  const mine = settings();  // this task's mechanism: its motor, encoder and ratio are its own
  const select = el("select", { id, onchange: (e) => {
    const m = ctx.app.motors.find((x) => x.key === e.target.value);
    mine.motor = e.target.value;
    if (m) { mine.cpr = String(m.cpr); mine["gear-ratio"] = String(m.gear_ratio); }
    save(); ctx.rerender();
  } }, el("option", { value: "", text: "not in the list / dead wheels" }));
  for (const m of ctx.app.motors) select.append(el("option", { value: m.key, text: `${m.name} (${m.cpr} counts per revolution)`, selected: m.key === mine.motor }));
  return el("div", { class: "field" }, el("label", { for: id, text: "Motor" }), select,
    el("small", { text: "fills in the counts per revolution of its built-in encoder; type them instead for another encoder. Kept for this task only" }));
}

export function render(host, ctx) {
  const t = ctx.state;
  host.append(el("h2", { text: ctx.task.title }), el("p", { class: "help", text: ctx.task.needs }));
  const input = el("input", { type: "file", multiple: true, id: "task-files" });
  const status = el("span", { role: "status" });
  input.addEventListener("change", async () => {
    const files = [...input.files];
    if (!files.length) return;
    status.textContent = "reading…";
    try { await addFiles(t, files); ctx.rerender(); } catch (e) { status.textContent = e.message; }
  });
  const drop = el("label", { class: "drop", for: "task-files" }, el("span", { text: t.files.length ? "Add more files" : "Choose or drop your files" }), input);
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", async (e) => { e.preventDefault(); drop.classList.remove("over"); await addFiles(t, [...e.dataTransfer.files]); ctx.rerender(); });
  host.append(el("section", { class: "card" }, drop, status, motorPicker(ctx),
    t.files.length ? el("ul", { class: "files" }, t.files.map((f) => fileRow(ctx, f))) : null));
  const first = t.files.find((f) => f.info && f.info.signals && f.info.signals.length);
  if (first) {
    const raw = el("details", { class: "raw" }, el("summary", { text: `The signals in ${first.name}` }));
    const area = el("div");
    raw.append(area);
    raw.addEventListener("toggle", () => { if (raw.open) plots.raw(area, first.info); });
    host.append(raw);
  }
  for (const [key, files] of groups(t)) host.append(groupCard(ctx, key, files));
  const done = Object.values(t.runs).some((r) => r.result);
  host.append(el("nav", { class: "next" }, el("a", { class: `button${done ? " primary" : ""}`, href: `#/${ctx.task.key}/gains`, text: "Gains for your code →" })));
}

// Run every analysis that has no result for its current files (the gains step's "add that file").
export async function runAll(ctx) {
  const t = ctx.state;
  const jobs = [];
  for (const [key, files] of groups(t)) {
    const run = t.runs[key];
    if (!run || !run.result || run.files.join("\n") !== files.map((f) => f.name).join("\n")) jobs.push(runGroup(ctx, key, files));
  }
  await Promise.all(jobs);
}
