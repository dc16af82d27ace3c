// The page's state, kept in IndexedDB (files included), so a reload restores the last results.
//
// Settings belong to the mechanism they describe, not to the app: each task (the drive's dead wheels, a
// mechanism, the bench motor) keeps its own encoder counts per revolution, wheel radius, gear ratio and motor
// (`task(key).settings`); the fields of a step read and write the settings of the task shown (`settings()`).
// Each task is stored as a record of its own ("task:<key>") and a tab writes only the tasks it changed, so two
// open tabs never overwrite each other's settings of another task; a result carries the settings it was fitted
// with (fit.js), so nothing typed in another tab changes an answer shown.
const DB = "motorlab-ui", STORE = "state", OLD_KEY = "v1";

export const SHARED_FIELDS = ["cpr", "wheel-radius", "gear-ratio"];  // the mechanism's settings, per task

export function emptyTask() {
  return { files: [], options: {}, settings: { motor: "" }, runs: {},
    gains: { target: "", loop: "velocity", options: {}, use: {}, typed: {}, language: "java" }, session: null };
}

// shared: what belongs to the app and no answer depends on (the robot's address).
export const state = { shared: {}, tasks: {} };

export function task(key) {
  if (!state.tasks[key]) state.tasks[key] = emptyTask();
  const t = state.tasks[key];
  if (!t.settings) t.settings = { motor: "" };
  return t;
}

let active = null;
// The task shown (main.js sets it at each view): the one whose settings the fields read and write.
export function setActive(key) { active = key || null; }
export function settings(key = active) { return key ? task(key).settings : {}; }

// What a tab last read or wrote of each record: a save writes only the records this tab changed since.
// A result's plots (thousands of numbers) are a record of their own ("plots:<result id>"), written once: a
// keystroke's save never copies them again.
const written = {};
const snapshot = (value) => JSON.stringify(value, (k, v) => (v instanceof Blob ? `${v.size}:${v.name || ""}` : k === "panels" ? undefined : v));

function records() {
  const out = [["shared", state.shared]];
  for (const [key, t] of Object.entries(state.tasks)) {
    const runs = {};
    for (const [k, r] of Object.entries(t.runs || {})) {
      if (r.panels && r.id) {
        runs[k] = { ...r, panels: undefined, plots: r.id };
        out.push([`plots:${r.id}`, r.panels]);
      } else runs[k] = r;
    }
    out.push([`task:${key}`, { ...t, runs }]);
  }
  return out;
}

function open() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB, 1);
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
  });
}

const request = (req) => new Promise((resolve, reject) => { req.onsuccess = () => resolve(req.result); req.onerror = () => reject(req.error); });

export async function load() {
  try {
    const db = await open();
    const store = db.transaction(STORE).objectStore(STORE);
    const [keys, values] = await Promise.all([request(store.getAllKeys()), request(store.getAll())]);
    const records = Object.fromEntries(keys.map((k, i) => [k, values[i]]));
    const old = records[OLD_KEY];
    if (old && old.tasks && !keys.some((k) => String(k).startsWith("task:"))) {
      // the state of an earlier version: one record, settings shared by every task. Each task takes the
      // settings its results were fitted with (their record), never another task's.
      for (const [key, t] of Object.entries(old.tasks)) records[`task:${key}`] = { ...t, settings: { motor: "" } };
      records.shared = { robot: (old.shared || {}).robot };
    }
    if (records.shared) state.shared = records.shared;
    for (const [k, t] of Object.entries(records)) {
      if (!String(k).startsWith("task:")) continue;
      const key = String(k).slice(5);
      state.tasks[key] = t;
      task(key);
      for (const run of Object.values(t.runs || {})) {
        if (run.status === "running") run.status = run.result ? "done" : "stopped";
        if (run.plots && records[`plots:${run.plots}`]) { run.panels = records[`plots:${run.plots}`]; written[`plots:${run.plots}`] = "kept"; }
      }
      if (t.session && t.session.status === "running") t.session.status = t.session.body ? "done" : "stopped";
      written[k] = snapshot(t);
    }
    written.shared = snapshot(state.shared);
    const unused = keys.filter((k) => String(k).startsWith("plots:") && !written[k]);  // plots of results replaced since
    if (unused.length) { const tx = db.transaction(STORE, "readwrite").objectStore(STORE); for (const k of unused) tx.delete(k); }
  } catch (e) { /* private mode or no IndexedDB: the page works, it only forgets on reload */ }
}

let timer = null;
export function save() {
  clearTimeout(timer);
  timer = setTimeout(async () => {
    try {
      const changed = records().filter(([k, v]) => (k.startsWith("plots:") ? !written[k] : written[k] !== snapshot(v)));
      if (!changed.length) return;
      const db = await open();
      const store = db.transaction(STORE, "readwrite").objectStore(STORE);
      for (const [k, v] of changed) { store.put(v, k); written[k] = k.startsWith("plots:") ? "kept" : snapshot(v); }
    } catch (e) { /* see load() */ }
  }, 200);
}

export async function forget() {
  state.shared = {}; state.tasks = {};
  for (const k of Object.keys(written)) delete written[k];
  try { const db = await open(); db.transaction(STORE, "readwrite").objectStore(STORE).clear(); } catch (e) { /* nothing kept */ }
}
