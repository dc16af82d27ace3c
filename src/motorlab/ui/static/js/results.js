// One analysis result for people: parameters in words with symbols, value ± uncertainty in one human-scaled unit.
import { el } from "./dom.js";
import { number, prettyUnit, quantity } from "./format.js";
import { parameterWords, plain } from "./words.js";

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
    ["Share of the variation the model explains (R²)", fit.r2 === null || fit.r2 === undefined ? "not determined" : number(fit.r2, 6)],
    ["Points used", fit.n_points === undefined ? "not determined" : String(fit.n_points)],
  ];
  if (fit.correlation) {
    const { names, matrix } = fit.correlation;
    const pairs = [];
    names.forEach((a, i) => names.forEach((b, j) => { if (j > i && Math.abs(matrix[i][j]) >= 0.5) pairs.push(`${parameterWords(a)[1] || a} and ${parameterWords(b)[1] || b}: ${number(matrix[i][j], 2)}`); }));
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
