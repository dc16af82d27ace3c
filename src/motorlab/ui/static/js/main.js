// motorlab ui: the page. Hash routes "#/<task>/<step>", one shared state (store.js), steps in steps/*.js.
import { $, el, keepFocus } from "./dom.js";
import { getJson } from "./api.js";
import * as plots from "./plots.js";
import { load, setActive, state, task as taskState } from "./store.js";
import { STEPS, TASKS, findTask, registerStep } from "./tasks.js";
import { setSchema } from "./words.js";
import * as choose from "./steps/choose.js";
import * as fit from "./steps/fit.js";
import * as session from "./steps/session.js";
import * as gains from "./steps/gains.js";
import "./steps/robot.js";  // the robot link: registers its task and steps (docs/robot.md)

registerStep("choose", choose);
registerStep("fit", fit);
registerStep("session", session);
registerStep("gains", gains);

export const app = { schema: null, motors: [] };

function parseHash() {
  const [taskKey, stepKey, ...rest] = location.hash.replace(/^#\/?/, "").split("/");
  const task = findTask(taskKey);
  if (!task) return { task: null, step: "choose", which: "" };
  const steps = task.steps.map(([k]) => k);
  // a third part names what the step shows: the results the gains come from (#/drive/gains/<result>)
  return { task, step: steps.includes(stepKey) ? stepKey : steps[0], which: decodeURIComponent(rest.join("/")) };
}

export const go = (taskKey, stepKey) => { location.hash = taskKey ? `#/${taskKey}/${stepKey}` : "#/"; };

function breadcrumb(task, step) {
  const nav = $("#steps");
  nav.replaceChildren();
  if (!task) return;
  nav.append(el("a", { href: "#/", text: "Tasks" }));
  task.steps.forEach(([key, title], k) => {
    nav.append(el("span", { class: "sep", text: "›", "aria-hidden": "true" }));
    nav.append(el("a", { href: `#/${task.key}/${key}`, text: `${k + 1}. ${title}`, "aria-current": key === step ? "step" : undefined }));
  });
}

let current = null;
// A redraw of the same view (a result arriving, an option changed) keeps the focused field, its caret and
// what is typed in it; a new view (a link, back, forward) starts afresh.
const rerender = () => keepFocus($("#view"), () => render({ fresh: false }));

// fresh: a view opened (a link, back, forward, the address typed), not a redraw of the one shown.
export function render({ fresh = true } = {}) {
  const { task, step, which } = parseHash();
  setActive(task && task.key);
  if (current && current.leave) current.leave();
  breadcrumb(task, step);
  const host = $("#view");
  host.replaceChildren();
  current = STEPS[step];
  const ctx = { app, task, which, fresh, state: task ? taskState(task.key) : null, go: (s) => go(task && task.key, s), rerender, goTask: go };
  document.title = task ? `motorlab · ${task.short}` : "motorlab";
  current.render(host, ctx);
  document.body.dataset.view = task ? `${task.key}/${step}` : "choose";
}

async function start() {
  await load();
  app.schema = await getJson("api/schema");
  app.motors = await getJson("api/motors");
  setSchema(app.schema);
  window.addEventListener("hashchange", () => { render(); window.scrollTo(0, 0); });
  render();
  document.body.dataset.ready = "true";
  // Plotly's one-time set-up, paid now (the task chooser shown) rather than when the first result is drawn
  const warm = () => plots.warmUp();
  if (window.requestIdleCallback) window.requestIdleCallback(warm, { timeout: 2000 }); else setTimeout(warm, 500);
}

start().catch((e) => { $("#view").replaceChildren(el("p", { class: "error", role: "alert", text: `The page could not start: ${e.message}. Reload it; if it stays, restart motorlab ui.` })); });
export { TASKS, state };
