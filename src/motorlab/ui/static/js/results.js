// One analysis result for people: parameters in words with symbols, value ± uncertainty in one human-scaled unit.
import { el } from "./dom.js";
import { correlation, number, prettyUnit, quantity, share } from "./format.js";
import { fieldLabel, parameterWords, plain } from "./words.js";

export function parameterTable(parameters, shaft) {
  const notes = Object.values(parameters || {}).some((p) => p && p.note);
  const rows = Object.entries(parameters || {}).map(([key, p]) => {
    const [name, symbol] = parameterWords(key);
    const determined = p.determined !== false && p.value !== null && p.value !== undefined;
    return el("tr", { "data-name": key },
      el("th", { scope: "row" }, name, symbol ? el("span", { class: "symbol", text: ` ${symbol}` }) : null),
      el("td", { class: "num value", "data-label": "value", text: determined ? quantity(p.value, p.stderr, p.unit) : "not determined" }),
      notes ? el("td", { class: "note", text: plain(p.note || "") }) : null);
  });
  return el("table", { class: "params" },
    el("caption", { text: shaft ? `At ${/^(the|a|an) /i.test(shaft) ? "" : "the "}${shaft}` : "The parameters" }),
    el("thead", {}, el("tr", {}, el("th", { scope: "col", text: "Parameter" }), el("th", { scope: "col", text: "Value" }), notes ? el("th", { scope: "col", text: "Note" }) : null)),
    el("tbody", {}, rows));
}

export function diagnostics(fit) {
  if (!fit) return null;
  const rows = [
    ["How far the data are from the model (RMS)", fit.rmse === null || fit.rmse === undefined ? "not determined" : `${number(fit.rmse, 3)} ${prettyUnit(fit.rmse_unit)}`],
    ["Share of the variation the model explains (R²)", share(fit.r2)],
    ["Points used", fit.n_points === undefined ? "not determined" : String(fit.n_points)],
  ];
  if (fit.correlation) {
    const { names, matrix } = fit.correlation;
    const pairs = [];
    names.forEach((a, i) => names.forEach((b, j) => { if (j > i && Math.abs(matrix[i][j]) >= 0.5) pairs.push(`${parameterWords(a)[1] || a} and ${parameterWords(b)[1] || b}: ${correlation(matrix[i][j])}`); }));
    rows.push(["Parameters the data tell apart poorly (correlation ≥ 0.5)", pairs.join("; ") || "none"]);
  }
  return el("table", { class: "diagnostics" }, el("caption", { text: "How well the model fits" }),
    el("tbody", {}, rows.map(([k, v]) => el("tr", {}, el("th", { scope: "row", text: k }), el("td", { text: v })))));
}

function shaftWords(details) {
  const s = details && details.shaft;
  if (!s) return "";
  return typeof s === "string" ? s : Object.values(s).join(", ");
}

export function result(r) {
  const items = Array.isArray(r) ? r : [r];
  return items.map((one) => {
    const left = ((one.details || {}).left_out || {}).text;  // said above the result, with "Put them back"
    const warnings = (one.warnings || []).filter((w) => w !== left);
    return el("div", { class: "result" },
      parameterTable(one.parameters, shaftWords(one.details)),
      warnings.length ? el("ul", { class: "warnings" }, warnings.map((w) => el("li", { text: plain(w) }))) : null,
      diagnostics(one.fit));
  });
}

// What a result says was left out of its log (time spans), or null.
export function leftOut(r) {
  const one = Array.isArray(r) ? r[0] : r;
  return (one && one.details && one.details.left_out) || null;
}

// ---- A result is a record of how it was made (issue 31) ----------------------------------------------------
// Its files (name, size, sha256), every setting it used (each option typed, the mechanism's counts per revolution,
// wheel radius and gear ratio, the time spans left out, the column rules), the units the file carries, and the
// command that gives the same answer. What is shown of a result (its gains, code, plots, the command) comes from
// its record; a setting changed afterwards makes it say so ("fitted with 8192 counts/rev; you now have 1120: fit
// again") and offer nothing to copy, never change it silently.

async function sha256(file) {
  try {
    const digest = await crypto.subtle.digest("SHA-256", await file.arrayBuffer());
    return [...new Uint8Array(digest)].map((b) => b.toString(16).padStart(2, "0")).join("");
  } catch (e) { return null; }  // crypto.subtle exists only on a secure page (this machine's address, or HTTPS)
}

// The values in force for `fields`: the mechanism's settings (`shared`, per task) and the fit's own options.
export function settingsUsed(fields, values, shared, isShared) {
  const out = {};
  for (const f of fields) {
    if (f.positional || f.kind === "file") continue;
    const v = isShared(f.name) ? shared[f.name] : values[f.name];
    if (v !== undefined && v !== null && String(v).trim() !== "") out[f.name] = String(v).trim();
  }
  return out;
}

export async function makeRecord({ experiment, files, fields, settings, ownUnits, columns, command }) {
  const hashed = await Promise.all(files.map(async (f) => {
    const blob = f.excluded && f.excluded.length ? f.trimmed || f.file : f.file;
    return { name: f.name, size: blob ? blob.size : null, sha256: blob ? await sha256(blob) : null };
  }));
  return { experiment, files: hashed, fields: fields.filter((f) => !f.positional && f.kind !== "file").map((f) => f.name),
    settings, own_units: ownUnits || null, columns: columns || [], command, made: new Date().toISOString() };
}

const SETTING_WORDS = { cpr: (v) => `${v} counts/rev`, "wheel-radius": (v) => `a wheel radius of ${v}`, "gear-ratio": (v) => `a gear ratio of ${v}` };

function settingWords(f, v) {
  const name = f ? fieldLabel(f).toLowerCase() : "";
  if (v === undefined || v === null || v === "") return f && SETTING_WORDS[f.name] ? `no ${name}` : `no ${name} given`;
  return f && SETTING_WORDS[f.name] ? SETTING_WORDS[f.name](v) : `${name} ${v}`;
}

// What differs between the settings a result was made with and those in force now: one sentence each.
export function changes(record, fields, now) {
  if (!record || !record.settings) return [];
  const byName = Object.fromEntries(fields.map((f) => [f.name, f]));
  const names = [...new Set([...Object.keys(record.settings), ...Object.keys(now)])].filter((n) => (record.fields || []).includes(n));
  return names.filter((n) => (record.settings[n] || "") !== (now[n] || ""))
    .map((n) => `fitted with ${settingWords(byName[n], record.settings[n])}; you now have ${now[n] || "none"}`);
}

// "How this result was made": files with their hash, the settings, the file's own units, the command.
export function recordView(record, fields = []) {
  if (!record) return null;
  const byName = Object.fromEntries(fields.map((f) => [f.name, f]));
  const settings = Object.entries(record.settings || {}).map(([k, v]) => `${byName[k] ? fieldLabel(byName[k]).toLowerCase() : k.replace(/-/g, " ")} ${v}`);
  const own = record.own_units;
  return el("details", { class: "record" }, el("summary", { text: "How this result was made" }),
    el("ul", {},
      record.files.map((f) => el("li", {}, `${f.name}`, el("span", { class: "hash", text: ` ${f.size === null ? "" : `${f.size} bytes, `}SHA-256 ${f.sha256 ? f.sha256.slice(0, 16) + "…" : "not computed"}` }))),
      own ? el("li", { text: `in the file's own units: ${own.units}${own.per_rotation ? ` (${number(own.per_rotation, 6)} per rotation)` : ""}` }) : null,
      settings.length ? el("li", { text: `settings: ${settings.join("; ")}` }) : el("li", { text: "no setting typed: the defaults" }),
      el("li", { text: `fitted ${String(record.made).slice(0, 16).replace("T", " ")} UTC` })));
}
