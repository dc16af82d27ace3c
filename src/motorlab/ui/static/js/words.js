// Every word the page shows for what motorlab names: read from /api/schema (the experiment descriptions and
// motorlab.glossary), never restated here (issue 33): field labels and help, each choice in words, experiment
// titles, parameter and gain names, targets, the tasks' titles. setSchema() fills the tables below once the
// schema has arrived (before the first view is drawn).
import { TASKS } from "./tasks.js";

export const EXPERIMENT_WORDS = {};  // experiment -> its description's title
export const GAIN_WORDS = {};        // gain in a target's code -> its name in words
export const MEASURED_BY = {};       // parameter -> the measurement that gives it
const FIELD_LABELS = {};             // option name -> its label (for server text that names a --option)
let PLAIN_WORDS = [];                // [RegExp, words]: an expert's term in the server's text -> a student's words

let SCHEMA = null;
export function setSchema(s) {
  SCHEMA = s;
  for (const [key, exp] of Object.entries(s.analyze || {})) {
    EXPERIMENT_WORDS[key] = exp.title;
    for (const f of exp.fields || []) FIELD_LABELS[f.name] = FIELD_LABELS[f.name] || f.label;
  }
  for (const command of ["characterize", "tune"]) for (const f of (s[command] || {}).fields || []) FIELD_LABELS[f.name] = FIELD_LABELS[f.name] || f.label;
  for (const [key, p] of Object.entries(s.parameters || {})) GAIN_WORDS[key] = p.name;
  Object.assign(GAIN_WORDS, s.gains || {});
  Object.assign(MEASURED_BY, s.measured_by || {});
  PLAIN_WORDS = (s.plain_words || []).map(([pattern, words]) => [new RegExp(pattern, "gu"), words]);
  for (const task of TASKS) Object.assign(task, (s.tasks || {})[task.key] || {});
}

const spoken = (name) => name.replace(/-/g, " ").replace(/^./, (c) => c.toUpperCase());

export function fieldLabel(f) { return f.label || spoken(f.name); }
// The label of an option by its name (the schema's label of "cpr"), for a page's own fields.
export function fieldWords(name) { return FIELD_LABELS[name] || spoken(name); }

// A choice in words: the schema's own for the field (choice_labels, in the order of its choices).
export function choiceLabel(f, value) {
  const k = (f.choices || []).findIndex((c) => String(c) === String(value));
  return (k >= 0 && f.choice_labels && f.choice_labels[k]) || String(value);
}
export function targetLabel(key) {
  const t = (SCHEMA && SCHEMA.targets || []).find((x) => x.key === key);
  return (t && t.label) || key;
}
export function parameterWords(key) {
  const p = SCHEMA && SCHEMA.parameters && SCHEMA.parameters[key];
  if (p) return [p.name, p.symbol || key];
  return [key.replace(/_over_/g, " / ").replace(/_/g, " "), ""];
}

// One-line help: without "(default …)" (the box shows the default) and "[unit]" (shown beside it); flags in words.
export function helpWords(f) {
  const raw = f.help || "";
  return plain(raw.replace(/\s*\((?:default|e\.g\.)?[^()]*default[^()]*\)/gi, "").replace(/\s*\[[^\]]*\]/g, "")
    .replace(/\s*\(\d[^()]*\)\s*$/, "").replace(/\s+—\s*default.*$/, "").trim());
}

// Server text (errors, notes, help, progress) with every "--option" named in words, so no flag shows outside a code
// box, and an expert's terms in a student's words (the schema's plain_words, motorlab.glossary.PLAIN_WORDS).
export function plain(text) {
  if (!text) return "";
  const named = String(text).replace(/(^|[^\w-])--([A-Za-z][\w-]*)/g, (m, pre, name) => `${pre}“${FIELD_LABELS[name] || name.replace(/-/g, " ")}”`);
  return PLAIN_WORDS.reduce((t, [pattern, words]) => t.replace(pattern, words), named);
}
