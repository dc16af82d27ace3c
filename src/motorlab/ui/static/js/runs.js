// Runs fitted together (a motor's locked-rotor runs, as `motorlab analyze stall A.csv B.csv C.csv`) and each run
// fitted alone: the joint answer is the result above; this table sets each run's own answer beside it, in words,
// so that a student sees what the runs agree on and what only their combination determines.
import { el } from "./dom.js";
import { run as runRequest } from "./api.js";
import { appendValues } from "./fields.js";
import { quantity } from "./format.js";
import { parameterWords, plain } from "./words.js";

// The answers set side by side (the rest is in the joint result above).
const HEADLINE = { stall: ["K", "R", "t_limit"], curve: ["K", "R", "Kt"] };

// Several files fitted as one run group: also fit each alone (after the joint fit, so the joint answer comes first).
export const fitsEachAlone = (files) => files.length > 1 && Boolean((files[0].info || {}).group);

// Fit each file alone with the same options; resolves to [{file, result} | {file, error}].
export async function fitEachAlone(exp, files, fields, values, columns, { signal } = {}) {
  return Promise.all(files.map(async (f) => {
    const form = new FormData();
    form.append("file", f.file, f.name);
    for (const rule of columns) form.append("column", rule);
    appendValues(form, fields, values);
    try {
      return { file: f.name, result: await runRequest(`api/analyze/${encodeURIComponent(exp)}`, form, { signal }) };
    } catch (e) {
      if (e && e.name === "AbortError") throw e;
      return { file: f.name, error: e.message };
    }
  }));
}

function cell(result, key) {
  const p = result && result.parameters && result.parameters[key];
  if (!p) return "—";
  return p.value === null || p.value === undefined ? "not determined" : quantity(p.value, p.stderr, p.unit);
}

// "Each run alone, and all runs together": one row per run, then the joint answer (the result above).
export function eachRunTable(exp, joint, each) {
  if (!each) return null;
  if (!each.length) return el("p", { class: "small", role: "status", text: "Fitting each run alone too, to set its answer beside the joint one…" });
  const keys = (HEADLINE[exp] || Object.keys(joint.parameters || {}).slice(0, 3)).filter((k) => (joint.parameters || {})[k]);
  const head = keys.map((k) => { const [name, symbol] = parameterWords(k); return el("th", { scope: "col" }, name, symbol ? el("span", { class: "symbol", text: ` ${symbol}` }) : null); });
  const rows = each.map((one) => el("tr", {}, el("th", { scope: "row", text: `${one.file} alone` }),
    one.error ? el("td", { colspan: keys.length, class: "error", text: plain(one.error) }) : keys.map((k) => el("td", { class: "num", text: cell(one.result, k) }))));
  rows.push(el("tr", { class: "joint" }, el("th", { scope: "row", text: `All ${each.length} runs together (the answer above)` }),
    keys.map((k) => el("td", { class: "num", text: cell(joint, k) }))));
  return el("div", { class: "scroll" }, el("table", { class: "each-run" },
    el("caption", { text: "Each run alone, and all runs together" }),
    el("thead", {}, el("tr", {}, el("th", { scope: "col", text: "Fitted from" }), head)), el("tbody", {}, rows)),
    el("p", { class: "small", text: "One run alone tells less than the runs together: its heating is seen at one current only. The answer above fits every run at once, as one command with every file does." }));
}
