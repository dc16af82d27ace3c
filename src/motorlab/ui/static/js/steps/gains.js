// Step "Gains for your code": the motor model from the results of this task the student chose (one, or an
// explicit combination whose rule is shown; never a silent choice), each used with the settings it was fitted
// with (its record: counts per revolution, the file's own units …); the student's library; the gains recompute
// as any option changes (as SysId's window). A result whose settings changed since says so and gives no code.
// The address names the results the gains come from (#/drive/gains/<result>), so it opens the same gains again.
import { commandBox, debounce, el, uid } from "../dom.js";
import { post, run as runRequest, isAbort } from "../api.js";
import { save, settings } from "../store.js";
import { argvOf, appendValues, field, isShared } from "../fields.js";
import { duration, number, overshoot, prettyUnit, settledError } from "../format.js";
import { GAIN_WORDS, MEASURED_BY, fieldWords, parameterWords, plain, targetLabel } from "../words.js";
import * as plots from "../plots.js";
import { addFiles, groups, runAll, staleness } from "./fit.js";

const OWN = ["loop", "kv", "ka", "ks", "params", "target", "emit", "unit"];
const PRIMARY = ["cpr", "wheel-radius", "units"];
const DISTANCES = ["m", "ft", "in"];  // tune's length units that are distances (metres, feet, inches)
const TYPED_UNITS = { K: "V*s/rad", R: "ohm", J: "kg*m^2", kV: "V*s/rad", kA: "V*s^2/rad", kS: "V" };
const LANGUAGES = [["java", "Java"], ["kotlin", "Kotlin"], ["python", "Python"]];
// The parameters of the motor model: two results giving one of them are two models, never merged silently.
const MODEL = ["kS", "kV", "kA", "kG", "K", "R", "L", "J", "b", "Tf"];
let controller = null;

const given = (p) => p && typeof p.value === "number" && p.determined !== false;
const listWords = (items) => (items.length > 1 ? `${items.slice(0, -1).join(", ")} and ${items[items.length - 1]}` : items[0] || "");

// The results of this task that can give the motor model: [{key, run, label, parameters}].
function candidates(ctx) {
  const t = ctx.state;
  const live = new Set(groups(t).keys());  // results of files still chosen, for what they are now said to measure
  const out = [];
  for (const [key, run] of Object.entries(t.runs)) {
    if (!run.result || !live.has(key)) continue;
    const one = Array.isArray(run.result) ? run.result[0] : run.result;
    out.push({ key, run, label: run.files.join(", "), parameters: one.parameters || {} });
  }
  return out;
}

// The results chosen: those ticked; a view opened by an address that names results ticks those.
function chosen(ctx, all) {
  const named = (ctx.which || "").split("+").filter(Boolean);
  const byUrl = all.filter((c) => named.includes(c.key));
  if (ctx.fresh && byUrl.length) for (const c of all) ctx.state.gains.use[c.key] = byUrl.includes(c);
  return all.filter((c) => ctx.state.gains.use[c.key] !== false);
}

// Parameters of the model given by more than one chosen result: {name: [labels]}.
function conflicts(list) {
  const by = {};
  for (const c of list) for (const k of MODEL) if (given(c.parameters[k])) (by[k] = by[k] || []).push(c);
  return Object.fromEntries(Object.entries(by).filter(([, cs]) => cs.length > 1));
}

// Each chosen result with the settings it was fitted with: a mechanism setting (counts per revolution, wheel
// radius, gear ratio) comes from the record of the result that used it, else from this task's settings.
function settingFor(list, name) {
  for (const c of list) {
    const r = c.run.record;
    if (r && (r.fields || []).includes(name)) return r.settings[name] || "";
  }
  return settings()[name] || "";
}

// The file's own units of the model (a SysId file in rotations: the gains in rotations), or null.
function ownUnits(list) {
  const own = list.map((c) => c.run.record && c.run.record.own_units).filter(Boolean);
  return own.length ? own[0] : null;
}

// The catalogue motor a session names (its encoder's counts per revolution), or null.
function sessionMotor(ctx) {
  const body = ctx.state.session && ctx.state.session.body;
  const m = body && body.results && body.results.session && body.results.session.motor;
  return m && m.counts_per_revolution ? m : null;
}

// The results the gains are designed from: [{name, doc, parameters}], plus values typed in.
function sources(ctx, list) {
  const t = ctx.state, out = [];
  if (ctx.task.key === "bench") {
    const body = t.session && t.session.body;
    if (body) {
      const units = Object.keys(body.results.units);
      const unit = t.gains.unit && units.includes(t.gains.unit) ? t.gains.unit : units[0];
      out.push({ name: "results.json", label: `the session's unit ${unit}`, doc: body.results, parameters: body.results.units[unit].parameters || {}, unit });
    }
  } else {
    list.forEach((c, k) => out.push({ name: `${c.run.experiment}-${k + 1}.json`, label: c.label, doc: c.run.result, parameters: c.parameters, key: c.key }));
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

// The options of the tune command: the gains' own options, and the mechanism's settings as the model's results
// were fitted with them (their records), a setting no result used from this task's settings.
function tuneValues(ctx, model) {
  const g = ctx.state.gains;
  const values = { ...g.options };
  for (const name of ["cpr", "wheel-radius", "gear-ratio"]) values[name] = settingFor(model, name);
  const motor = ctx.task.key === "bench" ? sessionMotor(ctx) : null;
  if (motor) values.cpr = String(motor.counts_per_revolution);  // the session's catalogue motor's encoder
  const own = ownUnits(model);
  const units = values.units || (own ? own.tune_units : "rad");
  // a file that logs distances (Meters, Feet, Inches) gives gains per its own length already: no wheel radius;
  // else a wheel radius turns lengths into distances at the wheel: only when a distance is the length unit (or
  // the target counts in inches: Road Runner's inPerTick, Pedro), never silently under a box that says radians
  if ((own && DISTANCES.includes(own.tune_units)) || !(DISTANCES.includes(units) || ["roadrunner", "pedro"].includes(g.target))) values["wheel-radius"] = "";
  return values;
}

function tuneForm(ctx, list, model, { emit } = {}) {
  const g = ctx.state.gains;
  const form = new FormData();
  form.append("loop", g.loop);
  form.append("target", g.target);
  if (emit) form.append("emit", emit);
  for (const s of list) form.append("params", new Blob([JSON.stringify(s.doc)], { type: "application/json" }), s.name);
  if (list.some((s) => s.unit)) form.append("unit", list.find((s) => s.unit).unit);
  const values = tuneValues(ctx, model);
  for (const f of tuneFields(ctx)) {
    const v = values[f.name];
    if (v !== undefined && v !== null && String(v).trim() !== "") form.append(f.name, String(v).trim());
  }
  return form;
}

const tuneFields = (ctx) => ctx.app.schema.tune.fields.filter((f) => !f.positional && !OWN.includes(f.name) && f.kind !== "file");

// Four significant digits, as every number of the page without an uncertainty: kS, kV and kA are measured to a
// fraction of a percent at best, and a gain closer than that changes nothing a robot does; the code to paste
// below keeps every digit the design gave.
function gainsTable(d) {
  const u = d.units || {};
  const row = (k, v) => el("tr", { "data-gain": k }, el("th", { scope: "row" }, GAIN_WORDS[k] ? GAIN_WORDS[k].replace(new RegExp(` ${k}$`), "") : k, el("span", { class: "symbol", text: ` ${k}` })),
    el("td", { class: "num", text: `${number(v)} ${prettyUnit(u[k] || "")}`.trim() }));
  const r = d.response || {};
  const unitOf = u.steady_state_error || "";
  return el("table", { class: "params", id: "gains-table" }, el("caption", { text: `Gains for ${targetLabel(d.target)}` }),
    el("tbody", {}, Object.entries(d.gains).map(([k, v]) => row(k, v)), Object.entries(d.feedforward).map(([k, v]) => row(k, v)),
      el("tr", {}, el("th", { scope: "row", text: "Rise time (10 to 90 %)" }), el("td", { class: "num", text: duration(r.rise_time) })),
      el("tr", {}, el("th", { scope: "row", text: "Overshoot" }), el("td", { class: "num", text: overshoot(r.overshoot) })),
      el("tr", {}, el("th", { scope: "row", text: "Settling time" }), el("td", { class: "num", text: duration(r.settling_time) })),
      el("tr", {}, el("th", { scope: "row", text: "Error left after settling" }), el("td", { class: "num", text: settledError(r.steady_state_error, (d.step || {}).size, unitOf) }))));
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

async function compute(ctx, out, list, model) {
  // a change typed in a view just left (its 350 ms pause ending after a link was followed) computes nothing:
  // it would stop the shown view's computation and leave it saying "computing the gains…" for ever
  if (!out.status.isConnected) return;
  const g = ctx.state.gains;
  if (controller) controller.abort();
  controller = new AbortController();
  const signal = controller.signal;
  out.status.textContent = "computing the gains…";
  out.error.textContent = "";
  try {
    // one run gives the gains (the CLI's tune JSON) and the simulated responses to plot
    const curves = await post("api/tune/response", tuneForm(ctx, list, model, { emit: g.language }), { signal });
    const d = curves.tune || await runRequest("api/tune", tuneForm(ctx, list, model, { emit: g.language }), { signal });
    const used = tuneValues(ctx, model);  // the settings these gains were made with, for a step that sends them on
    g.last = d; g.lastSettings = { cpr: used.cpr || "", "wheel-radius": used["wheel-radius"] || "" }; save();
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

// The choice of the motor model in words: a box per result; two results giving the same parameter are two
// models, and the student picks one (nothing is computed until then); results that complete each other are
// combined by a rule said in words.
function modelCard(ctx, all, model) {
  const t = ctx.state, g = t.gains;
  const card = el("section", { class: "card model" }, el("h3", { text: "The motor model, from" }));
  const pick = (keys) => {
    for (const c of all) g.use[c.key] = keys.includes(c.key);
    save();
    history.replaceState(null, "", `#/${ctx.task.key}/gains/${keys.map(encodeURIComponent).join("+")}`);
    ctx.rerender();
  };
  for (const c of all) {
    const id = uid("use");
    const names = Object.keys(c.parameters).filter((k) => given(c.parameters[k])).map((k) => parameterWords(k)[1] || k).join(", ");
    const on = model.includes(c);
    card.append(el("div", { class: "field flag" }, el("input", { type: "checkbox", id, checked: on,
      onchange: (e) => pick(all.filter((x) => (x === c ? e.target.checked : model.includes(x))).map((x) => x.key)) }),
      el("label", { for: id, text: `${c.label} (${names})` })));
  }
  const clash = conflicts(model);
  if (Object.keys(clash).length) {
    const involved = [...new Set(Object.values(clash).flat())];
    const what = (c) => Object.keys(clash).filter((k) => clash[k].includes(c)).join(", ");
    card.append(el("div", { class: "clash", role: "alert" },
      el("p", { text: `${listWords(involved.map((c) => c.label))} each give ${what(involved[0])}: they are ${involved.length === 2 ? "two" : "several"} models (another mechanism, another fit). The gains come from one: choose which.` }),
      el("div", { class: "actions" }, involved.map((c) => el("button", { type: "button", class: "primary", text: `Use ${c.label} only`,
        onclick: () => pick(model.filter((x) => x === c || !involved.includes(x)).map((x) => x.key)) })))));
  } else if (model.length > 1) {
    const parts = model.map((c) => `${Object.keys(c.parameters).filter((k) => MODEL.includes(k) && given(c.parameters[k])).map((k) => parameterWords(k)[1] || k).join(", ")} from ${c.label}`);
    card.append(el("p", { class: "rule", text: `The model combines ${listWords(parts)}: each value from the one result that gives it.` }));
  }
  return [card, Object.keys(clash).length > 0];
}

// A result whose settings changed since it was fitted: what changed, and where to fit it again. No gains then.
function staleCard(ctx, stale) {
  return el("section", { class: "card stale", role: "alert" }, el("h3", { text: "Fit again before you copy any gains" }),
    stale.map(([c, words]) => el("p", { text: `${c.label}: ${words.join("; ")}: fit again.` })),
    el("p", {}, "The gains would mix two settings, so none are shown. ",
      el("a", { href: `#/${ctx.task.key}/${ctx.task.steps[0][0]}`, text: "Fit again with what you have now" }),
      ", or type the setting back as it was."));
}

export function render(host, ctx) {
  const t = ctx.state, g = t.gains;
  const bench = ctx.task.key === "bench";
  const all = bench ? [] : candidates(ctx);
  const model = bench ? [] : chosen(ctx, all);
  if (!bench && model.length) {  // the address names the results the gains come from: it opens them again
    const want = `#/${ctx.task.key}/gains/${model.map((c) => encodeURIComponent(c.key)).join("+")}`;
    if (location.hash !== want) history.replaceState(null, "", want);
  }
  const own = ownUnits(model);
  const modelKey = model.map((c) => c.key).join("+");
  if (g.model !== modelKey) {  // another model: the defaults follow its file (an FRC SysId file: WPILib, in its units)
    g.model = modelKey;
    if (own) { g.target = "wpilib"; g.options.units = own.tune_units; }
  }
  if (!g.target || !targets(ctx).includes(g.target)) g.target = own ? "wpilib" : ctx.task.target(t);
  host.append(el("h2", { text: "Gains for your code" }));
  const list = sources(ctx, model);
  const have = known(list);
  let clash = false;
  if (!bench) {
    const [card, clashing] = modelCard(ctx, all, model);
    clash = clashing;
    if (!list.length) card.append(el("p", { text: "No result yet: " }, el("a", { href: `#/${ctx.task.key}/${ctx.task.steps[0][0]}`, text: "go back and run the fit" }), ", or type values below."));
    host.append(card);
  } else {
    const card = el("section", { class: "card" }, el("h3", { text: "The motor model, from" }));
    if (list.length) {
      const body = t.session.body, id = uid("unit");
      const select = el("select", { id, onchange: (e) => { g.unit = e.target.value; save(); ctx.rerender(); } },
        Object.entries(body.results.units).map(([k, u]) => el("option", { value: k, text: u.label || k, selected: k === list[0].unit })));
      card.append(el("div", { class: "field" }, el("label", { for: id, text: "Which motor of the session" }), select));
    } else card.append(el("p", { text: "No result yet: " }, el("a", { href: `#/${ctx.task.key}/${ctx.task.steps[0][0]}`, text: "go back and run the session" }), ", or type values below."));
    host.append(card);
  }
  const lack = missing(have);
  const out = { status: el("span", { role: "status" }), error: el("p", { class: "error", role: "alert" }), result: el("div", { id: "gains-result" }), plots: el("div", { class: "plots" }) };
  const stale = () => model.map((c) => [c, staleness(ctx, c.run)]).filter(([, w]) => w.length);
  const late = stale();
  const recompute = debounce(() => {
    // a setting typed here that the fit used: say so at once; typed back as it was: the gains again
    if (stale().length || late.length) { ctx.rerender(); return; }
    if (!missing(known(sources(ctx, model))).length) compute(ctx, out, sources(ctx, model), model);
  }, 350);
  const rerenderCommand = () => { const box = host.querySelector("details.command"); if (box) box.replaceWith(command()); };
  const changed = () => { recompute(); rerenderCommand(); };
  const motor = bench ? sessionMotor(ctx) : null;
  const fields = tuneFields(ctx).filter((f) => !(motor && f.name === "cpr"));  // the session's motor names its encoder
  const primary = fields.filter((f) => PRIMARY.includes(f.name));
  const more = fields.filter((f) => !PRIMARY.includes(f.name));
  const wanted = ((ctx.app.schema.targets || []).find((x) => x.key === g.target) || {}).needs || [];
  const usedBy = (name) => model.find((c) => c.run.record && (c.run.record.fields || []).includes(name));
  const note = (f) => {
    const fit = isShared(f.name) && usedBy(f.name);
    if (fit) return `as ${fit.label} was fitted with it`;
    if (f.name === "wheel-radius" && own && DISTANCES.includes(own.tune_units)) return "not used: the file logs distances";
    if (f.name === "wheel-radius" && !["roadrunner", "pedro"].includes(g.target)) return "used when the length unit is metres, feet or inches";
    if (f.name === "units" && own) return `the file's own unit is ${own.units.toLowerCase()}`;
    return wanted.includes(f.name) && !settings()[f.name] ? `needed for ${targetLabel(g.target)}` : "";
  };
  const language = uid("lang");
  const spec = (ctx.app.schema.targets || []).find((x) => x.key === g.target);
  const languages = spec && spec.languages ? LANGUAGES.filter(([k]) => spec.languages.includes(k)) : LANGUAGES;
  if (!languages.some(([k]) => k === g.language)) g.language = languages[0][0];
  const command = () => {
    const values = tuneValues(ctx, model);
    const argv = tuneFields(ctx).filter((f) => values[f.name] !== undefined && String(values[f.name]).trim() !== "")
      .map((f) => `--${f.name}=${String(values[f.name]).trim()}`);
    return commandBox(["tune", g.loop, ...list.map((s) => `--params=${s.name}`), `--target=${g.target}`, ...argv, `--emit=${g.language}`]);
  };
  host.append(el("section", { class: "card" }, targetPicker(ctx, changed), loopPicker(ctx, changed),
    el("div", { class: "options" }, primary.map((f) => field(f, g.options, changed, { note: note(f) })),
      motor ? el("p", { class: "small", text: `${fieldWords("cpr")}: ${motor.counts_per_revolution}, of the session's motor (${motor.name}).` }) : null,
      el("div", { class: "field" }, el("label", { for: language, text: "Code language" }),
        el("select", { id: language, onchange: (e) => { g.language = e.target.value; save(); changed(); } }, languages.map(([k, w]) => el("option", { value: k, text: w, selected: k === g.language }))))),
    el("details", { class: "more" }, el("summary", { text: "More settings (design method, tolerances, loop period, delay)" }),
      el("div", { class: "options" }, more.map((f) => field(f, g.options, changed)))),
    command()));
  if (late.length) { g.last = null; host.append(staleCard(ctx, late)); return; }
  if (clash) { g.last = null; return; }
  if (lack.length) { host.append(needsBlock(ctx, lack)); return; }
  host.append(el("section", { class: "card" }, el("div", { class: "actions" }, out.status), out.error, out.result, out.plots));
  compute(ctx, out, list, model);
}
