// Step "Gains for your code": one motor model merged from every result of this task (and values typed in),
// the student's library, the shared settings; the gains recompute as any option changes (as SysId's window).
import { commandBox, debounce, el, uid } from "../dom.js";
import { post, run as runRequest, isAbort } from "../api.js";
import { save, state } from "../store.js";
import { argvOf, appendValues, field, isShared } from "../fields.js";
import { duration, number, overshoot, prettyUnit, quantity } from "../format.js";
import { GAIN_WORDS, MEASURED_BY, fieldWords, parameterWords, plain, targetLabel } from "../words.js";
import * as plots from "../plots.js";
import { addFiles, groups, runAll } from "./fit.js";

const OWN = ["loop", "kv", "ka", "ks", "params", "target", "emit", "unit"];
const PRIMARY = ["cpr", "wheel-radius", "units"];
const TYPED_UNITS = { K: "V*s/rad", R: "ohm", J: "kg*m^2", kV: "V*s/rad", kA: "V*s^2/rad", kS: "V" };
const LANGUAGES = [["java", "Java"], ["kotlin", "Kotlin"], ["python", "Python"]];
let controller = null;

// The results the gains are designed from: [{name, blob, parameters}], plus values typed in.
function sources(ctx) {
  const t = ctx.state, out = [];
  if (ctx.task.key === "bench") {
    const body = t.session && t.session.body;
    if (body) {
      const units = Object.keys(body.results.units);
      const unit = t.gains.unit && units.includes(t.gains.unit) ? t.gains.unit : units[0];
      out.push({ name: "results.json", label: `the session's unit ${unit}`, doc: body.results, parameters: body.results.units[unit].parameters || {}, unit });
    }
  } else {
    const live = new Set(groups(t).keys());  // results of files still chosen, for what they are now said to measure
    let k = 0;
    for (const [key, run] of Object.entries(t.runs)) {
      if (!run.result || t.gains.use[key] === false || !live.has(key)) continue;
      const one = Array.isArray(run.result) ? run.result[0] : run.result;
      out.push({ name: `${run.experiment}-${++k}.json`, label: run.files.join(", "), doc: run.result, parameters: one.parameters || {}, key });
    }
  }
  const typed = Object.entries(t.gains.typed || {}).filter(([, v]) => v !== "" && Number.isFinite(parseFloat(v)));
  if (typed.length) {
    const parameters = Object.fromEntries(typed.map(([k, v]) => [k, { value: parseFloat(v), unit: TYPED_UNITS[k] }]));
    out.push({ name: "typed.json", label: "the values you typed", doc: { experiment: "typed", parameters }, parameters });
  }
  return out;
}

function known(list) {
  const have = new Set();
  for (const s of list) for (const [k, p] of Object.entries(s.parameters)) if (p && typeof p.value === "number" && p.determined !== false) have.add(k);
  return have;
}

// What the model still lacks: [] when kS/kV/kA or K, R, J are all known.
function missing(have) {
  if (have.has("kV") && have.has("kA")) return [];
  if (["K", "R", "J"].every((k) => have.has(k))) return [];
  if (have.has("kV") || have.has("kA")) return ["kV", "kA"].filter((k) => !have.has(k));
  return ["K", "R", "J"].filter((k) => !have.has(k));
}

function needsBlock(ctx, lack) {
  const t = ctx.state;
  const box = el("section", { class: "card needs", role: "note" },
    el("h3", { text: "The gains need a little more" }),
    el("p", { text: "The motor model is missing:" }));
  for (const key of lack) {
    const [words, symbol] = parameterWords(key);
    const id = uid("typed");
    box.append(el("div", { class: "need" },
      el("p", {}, el("strong", { text: `${words} ${symbol}` }), `: measured by ${MEASURED_BY[key] || "another experiment"}.`),
      el("div", { class: "field" }, el("label", { for: id }, `Type the ${words.toLowerCase()} if you know it`, el("span", { class: "unit", text: ` in ${prettyUnit(TYPED_UNITS[key])}` })),
        el("div", { class: "actions" },
          el("input", { type: "text", id, inputmode: "decimal", value: t.gains.typed[key] || "", onchange: (e) => { t.gains.typed[key] = e.target.value.trim(); save(); ctx.rerender(); } }),
          el("button", { type: "button", text: "Use this value" })))));
  }
  if (ctx.task.key !== "bench") {
    const id = uid("add");
    const input = el("input", { type: "file", id, multiple: true });
    const status = el("span", { role: "status" });
    input.addEventListener("change", async () => {
      status.textContent = "reading and fitting…";
      try { await addFiles(t, [...input.files]); await runAll(ctx); } catch (e) { status.textContent = e.message; }
    });
    box.append(el("label", { class: "drop small", for: id }, el("span", { text: "Add the file of that measurement (it is fitted with the settings you gave)" }), input), status);
  }
  return box;
}

function targets(ctx) {
  const fromSchema = ctx.app.schema.tune.fields.find((f) => f.name === "target");
  const all = [...(fromSchema ? fromSchema.choices : []), ...((ctx.app.schema.targets || []).map((x) => x.key))];
  const unique = [...new Set([...ctx.task.targets, ...all])];
  return unique.filter((k) => all.includes(k));
}

function targetPicker(ctx, onChange) {
  const g = ctx.state.gains;
  const name = uid("target");
  return el("fieldset", { class: "targets" }, el("legend", { text: "Your library" }),
    targets(ctx).map((key) => el("label", { class: "choice" },
      el("input", { type: "radio", name, value: key, checked: key === g.target, onchange: () => { g.target = key; save(); ctx.rerender(); } }),
      el("span", { text: targetLabel(key) }))));
}

function loopPicker(ctx, onChange) {
  const g = ctx.state.gains, name = uid("loop");
  return el("fieldset", { class: "targets" }, el("legend", { text: fieldWords("loop") }),
    [["velocity", "speed"], ["position", "position"]].map(([key, words]) => el("label", { class: "choice" },
      el("input", { type: "radio", name, value: key, checked: key === g.loop, onchange: () => { g.loop = key; save(); onChange(); } }), el("span", { text: words }))));
}

function tuneForm(ctx, list, { emit } = {}) {
  const g = ctx.state.gains;
  const form = new FormData();
  form.append("loop", g.loop);
  form.append("target", g.target);
  if (emit) form.append("emit", emit);
  for (const s of list) form.append("params", new Blob([JSON.stringify(s.doc)], { type: "application/json" }), s.name);
  if (list.some((s) => s.unit)) form.append("unit", list.find((s) => s.unit).unit);
  return appendValues(form, tuneFields(ctx), g.options);
}

const tuneFields = (ctx) => ctx.app.schema.tune.fields.filter((f) => !f.positional && !OWN.includes(f.name) && f.kind !== "file");

function gainsTable(d) {
  const u = d.units || {};
  const row = (k, v) => el("tr", { "data-gain": k }, el("th", { scope: "row" }, GAIN_WORDS[k] ? GAIN_WORDS[k].replace(new RegExp(` ${k}$`), "") : k, el("span", { class: "symbol", text: ` ${k}` })),
    el("td", { class: "num", text: `${number(v, 6)} ${prettyUnit(u[k] || "")}`.trim() }));
  const r = d.response || {};
  const unitOf = u.steady_state_error || "";
  return el("table", { class: "params", id: "gains-table" }, el("caption", { text: `Gains for ${targetLabel(d.target)}` }),
    el("tbody", {}, Object.entries(d.gains).map(([k, v]) => row(k, v)), Object.entries(d.feedforward).map(([k, v]) => row(k, v)),
      el("tr", {}, el("th", { scope: "row", text: "Rise time (10 to 90 %)" }), el("td", { class: "num", text: duration(r.rise_time) })),
      el("tr", {}, el("th", { scope: "row", text: "Overshoot" }), el("td", { class: "num", text: overshoot(r.overshoot) })),
      el("tr", {}, el("th", { scope: "row", text: "Settling time" }), el("td", { class: "num", text: duration(r.settling_time) })),
      el("tr", {}, el("th", { scope: "row", text: "Error left after settling" }), el("td", { class: "num", text: quantity(r.steady_state_error, null, unitOf) }))));
}

function snippetBox(code, language) {
  const button = el("button", { type: "button", class: "copy", "data-lang": language, text: "Copy the code" });
  const pre = el("pre", {}, el("code", { text: code }));
  button.addEventListener("click", async () => {
    try { await navigator.clipboard.writeText(code); }
    catch (e) { const range = document.createRange(); range.selectNodeContents(pre); getSelection().removeAllRanges(); getSelection().addRange(range); document.execCommand("copy"); }
    button.textContent = "Copied";
  });
  return el("div", { class: "snippet" }, el("header", {}, el("span", { text: "The code to paste" }), button), pre);
}

async function compute(ctx, out, list) {
  const g = ctx.state.gains;
  if (controller) controller.abort();
  controller = new AbortController();
  const signal = controller.signal;
  out.status.textContent = "computing the gains…";
  out.error.textContent = "";
  try {
    // one run gives the gains (the CLI's tune JSON) and the simulated responses to plot
    const curves = await post("api/tune/response", tuneForm(ctx, list, { emit: g.language }), { signal });
    const d = curves.tune || await runRequest("api/tune", tuneForm(ctx, list, { emit: g.language }), { signal });
    g.last = d; save();
    out.result.replaceChildren(gainsTable(d),
      el("ul", { class: "notes" }, [...d.conversion, ...d.notes].map((n) => el("li", { text: plain(n) }))),
      d.warnings.length ? el("ul", { class: "warnings" }, d.warnings.map((w) => el("li", { text: plain(w) }))) : "",
      d.snippet ? snippetBox(d.snippet, g.language) : "");
    plots.response(out.plots, curves);
    out.status.textContent = "";
  } catch (e) {
    if (isAbort(e)) return;
    out.status.textContent = "";
    out.error.textContent = e.message;
  }
}

export function render(host, ctx) {
  const t = ctx.state, g = t.gains;
  if (!g.target || !targets(ctx).includes(g.target)) g.target = ctx.task.target(t);
  host.append(el("h2", { text: "Gains for your code" }));
  const list = sources(ctx);
  const have = known(list);
  const model = el("section", { class: "card" }, el("h3", { text: "The motor model, from" }));
  if (!list.length) model.append(el("p", { text: "No result yet: ", }, el("a", { href: `#/${ctx.task.key}/${ctx.task.steps[0][0]}`, text: "go back and run the fit" }), ", or type values below."));
  if (ctx.task.key !== "bench") {
    const live = new Set(groups(t).keys());
    for (const [key, run] of Object.entries(t.runs)) {
      if (!run.result || !live.has(key)) continue;
      const id = uid("use");
      const one = Array.isArray(run.result) ? run.result[0] : run.result;
      const names = Object.keys(one.parameters || {}).map((k) => parameterWords(k)[1] || k).join(", ");
      model.append(el("div", { class: "field flag" }, el("input", { type: "checkbox", id, checked: g.use[key] !== false, onchange: (e) => { g.use[key] = e.target.checked; save(); ctx.rerender(); } }),
        el("label", { for: id, text: `${run.files.join(", ")} (${names})` })));
    }
  } else if (list.length) {
    const body = t.session.body, id = uid("unit");
    const select = el("select", { id, onchange: (e) => { g.unit = e.target.value; save(); ctx.rerender(); } },
      Object.entries(body.results.units).map(([k, u]) => el("option", { value: k, text: u.label || k, selected: k === list[0].unit })));
    model.append(el("div", { class: "field" }, el("label", { for: id, text: "Which motor of the session" }), select));
  }
  host.append(model);
  const lack = missing(have);
  const out = { status: el("span", { role: "status" }), error: el("p", { class: "error", role: "alert" }), result: el("div", { id: "gains-result" }), plots: el("div", { class: "plots" }) };
  const recompute = debounce(() => { if (!missing(known(sources(ctx))).length) compute(ctx, out, sources(ctx)); }, 350);
  const rerenderCommand = () => { const box = host.querySelector("details.command"); if (box) box.replaceWith(command()); };
  const changed = () => { recompute(); rerenderCommand(); };
  const fields = tuneFields(ctx);
  const primary = fields.filter((f) => PRIMARY.includes(f.name));
  const more = fields.filter((f) => !PRIMARY.includes(f.name));
  const wanted = ((ctx.app.schema.targets || []).find((x) => x.key === g.target) || {}).needs || [];
  const note = (f) => (wanted.includes(f.name) && !state.shared[f.name] ? `needed for ${targetLabel(g.target)}`
    : isShared(f.name) && state.shared[f.name] ? "as you gave it in the first step" : "");
  const language = uid("lang");
  const spec = (ctx.app.schema.targets || []).find((x) => x.key === g.target);
  const languages = spec && spec.languages ? LANGUAGES.filter(([k]) => spec.languages.includes(k)) : LANGUAGES;
  if (!languages.some(([k]) => k === g.language)) g.language = languages[0][0];
  const command = () => commandBox(["tune", g.loop, ...list.map((s) => `--params=${s.name}`), `--target=${g.target}`, ...argvOf(fields, g.options), `--emit=${g.language}`]);
  host.append(el("section", { class: "card" }, targetPicker(ctx, changed), loopPicker(ctx, changed),
    el("div", { class: "options" }, primary.map((f) => field(f, g.options, changed, { note: note(f) })),
      el("div", { class: "field" }, el("label", { for: language, text: "Code language" }),
        el("select", { id: language, onchange: (e) => { g.language = e.target.value; save(); changed(); } }, languages.map(([k, w]) => el("option", { value: k, text: w, selected: k === g.language }))))),
    el("details", { class: "more" }, el("summary", { text: "More settings (design method, tolerances, loop period, delay)" }),
      el("div", { class: "options" }, more.map((f) => field(f, g.options, changed)))),
    command()));
  if (lack.length) { host.append(needsBlock(ctx, lack)); return; }
  host.append(el("section", { class: "card" }, el("div", { class: "actions" }, out.status), out.error, out.result, out.plots));
  compute(ctx, out, list);
}
