// Form fields from /api/schema, labelled in words. The mechanism's settings (counts per revolution, wheel radius…)
// read and write the settings of the task shown (store.settings()), so what the student typed once is what its steps use.
import { el, uid } from "./dom.js";
import { prettyUnit } from "./format.js";
import { choiceLabel, fieldLabel, helpWords } from "./words.js";
import { SHARED_FIELDS, save, settings } from "./store.js";

export const isShared = (name) => SHARED_FIELDS.includes(name);

// One field: label (words, unit), input, one-line help. values[name] holds what was typed.
export function field(f, values, onChange, { note = "" } = {}) {
  const id = uid(`field-${f.name}`);
  const shared = isShared(f.name);
  const current = shared ? (settings()[f.name] ?? "") : (values[f.name] ?? "");
  const set = (v) => {
    if (shared) settings()[f.name] = v; else values[f.name] = v;
    save(); onChange && onChange(f.name, v);
  };
  let input;
  if (f.kind === "flag") {
    input = el("input", { type: "checkbox", id, name: f.name, checked: current === "true", onchange: (e) => set(e.target.checked ? "true" : "") });
  } else if (f.kind === "choice") {
    input = el("select", { id, name: f.name, onchange: (e) => set(e.target.value) });
    input.append(el("option", { value: "", text: f.default !== null && f.default !== undefined ? `${choiceLabel(f, f.default)} (default)` : "automatic" }));
    for (const c of f.choices) input.append(el("option", { value: String(c), text: choiceLabel(f, c), selected: String(c) === String(current) }));
  } else {
    const placeholder = f.default !== null && f.default !== undefined && f.default !== "" ? `default ${f.default}` : (f.unit ? `e.g. in ${prettyUnit(f.unit)}` : "");
    input = el("input", { type: "text", id, name: f.name, value: current, placeholder, autocomplete: "off", spellcheck: "false",
      inputmode: f.unit && f.unit !== "unit" ? "decimal" : undefined, oninput: (e) => set(e.target.value.trim()) });
  }
  const unit = f.unit && !["1", "count", "unit"].includes(f.unit) ? el("span", { class: "unit", text: ` in ${prettyUnit(f.unit)}` }) : null;
  const label = el("label", { for: id }, fieldLabel(f), unit, f.required ? el("span", { class: "unit", text: " (needed)" }) : null);
  const help = helpWords(f);
  const extra = [note, shared ? "used in both steps of this task" : ""].filter(Boolean).join(" · ");
  return el("div", { class: `field${f.kind === "flag" ? " flag" : ""}`, "data-field": f.name }, label, input,
    help || extra ? el("small", { text: [help, extra].filter(Boolean).join(" · ") }) : null);
}

// The command-line arguments of the typed values (for FormData and the "same as a command" box).
export function typedValues(fields, values) {
  const out = [];
  for (const f of fields) {
    if (f.positional || f.kind === "file") continue;
    const v = isShared(f.name) ? settings()[f.name] : values[f.name];
    if (v === undefined || v === null || String(v).trim() === "") continue;
    // a repeatable option typed as a list ("12.5:14, 20:21"): one value each, as the command line repeats it
    const items = f.type === "spans" ? String(v).split(/[,;]/).map((x) => x.trim()).filter(Boolean) : [String(v).trim()];
    for (const item of items) out.push([f.name, item, f.kind]);
  }
  return out;
}

export function appendValues(form, fields, values) {
  for (const [name, v] of typedValues(fields, values)) form.append(name, v);
  return form;
}

export function argvOf(fields, values) {
  return typedValues(fields, values).map(([name, v, kind]) => (kind === "flag" ? `--${name}` : `--${name}=${v}`));
}
