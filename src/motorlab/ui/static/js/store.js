// One state for every step and task, kept in IndexedDB (files included), so a reload restores the last results.
const DB = "motorlab-ui", STORE = "state", KEY = "v1";

export const SHARED_FIELDS = ["cpr", "wheel-radius", "gear-ratio"];

export function emptyTask() {
  return { files: [], options: {}, runs: {}, gains: { target: "", loop: "velocity", options: {}, use: {}, typed: {}, language: "java" }, session: null };
}

export const state = { shared: { motor: "" }, tasks: {} };

export function task(key) {
  if (!state.tasks[key]) state.tasks[key] = emptyTask();
  return state.tasks[key];
}

function open() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB, 1);
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
  });
}

export async function load() {
  try {
    const db = await open();
    const saved = await new Promise((resolve, reject) => {
      const req = db.transaction(STORE).objectStore(STORE).get(KEY);
      req.onsuccess = () => resolve(req.result); req.onerror = () => reject(req.error);
    });
    if (saved && saved.shared && saved.tasks) { state.shared = saved.shared; state.tasks = saved.tasks; }
    for (const t of Object.values(state.tasks)) for (const run of Object.values(t.runs || {})) if (run.status === "running") run.status = "stopped";
  } catch (e) { /* private mode or no IndexedDB: the page works, it only forgets on reload */ }
}

let timer = null;
export function save() {
  clearTimeout(timer);
  timer = setTimeout(async () => {
    try {
      const db = await open();
      const copy = { shared: state.shared, tasks: state.tasks };
      db.transaction(STORE, "readwrite").objectStore(STORE).put(copy, KEY);
    } catch (e) { /* see load() */ }
  }, 200);
}

export async function forget() {
  state.shared = { motor: "" }; state.tasks = {};
  try { const db = await open(); db.transaction(STORE, "readwrite").objectStore(STORE).delete(KEY); } catch (e) { /* nothing kept */ }
}
