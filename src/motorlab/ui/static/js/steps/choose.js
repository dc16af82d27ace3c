// The first screen: what the student wants to do, in their words, and which files that takes.
import { el } from "../dom.js";
import { TASKS } from "../tasks.js";
import { forget, task as taskState } from "../store.js";
import { addFiles } from "./fit.js";
import { addSessionFiles } from "./session.js";

export function render(host, ctx) {
  host.append(el("h2", { text: "What do you want to do?" }));
  const list = el("div", { class: "tasks" });
  for (const t of TASKS) {
    const s = taskState(t.key);
    const done = Object.values(s.runs || {}).filter((r) => r.result).length + (s.session && s.session.body ? 1 : 0);
    list.append(el("a", { class: "task", href: `#/${t.key}/${t.steps[0][0]}`, "data-task": t.key },
      el("strong", { text: t.title }), el("span", { text: t.needs }),
      done ? el("em", { text: `${done} result${done > 1 ? "s" : ""} kept from last time` }) : null));
  }
  host.append(list);

  const status = el("p", { class: "status", role: "status" });
  const input = el("input", { type: "file", multiple: true, id: "any-file" });
  // several files at once, chosen or dropped: a motor's runs are fitted together (motorlab analyze stall A B C)
  const take = async (files) => {
    if (!files.length) return;
    status.textContent = "reading…";
    if (files.some((f) => /\.(toml|zip)$/i.test(f.name))) {
      addSessionFiles(taskState("bench"), files);
      ctx.goTask("bench", "session");
      return;
    }
    const scratch = { files: [], options: {}, runs: {} };
    try { await addFiles(scratch, files); } catch (e) { status.textContent = e.message; return; }
    const first = scratch.files.find((f) => f.info && !f.info.error) || scratch.files[0];
    const key = (first.info && first.info.task) || "expert";
    const target = taskState(key);
    target.files.push(...scratch.files);
    ctx.goTask(key, "fit");
  };
  input.addEventListener("change", () => take([...input.files]));
  const drop = el("label", { class: "drop", for: "any-file" }, el("span", { text: "Choose or drop any log (or several): motorlab says what each is and which task it belongs to" }), input);
  drop.addEventListener("dragover", (e) => { e.preventDefault(); drop.classList.add("over"); });
  drop.addEventListener("dragleave", () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => { e.preventDefault(); drop.classList.remove("over"); take([...e.dataTransfer.files]); });
  host.append(el("section", { class: "card" }, el("h3", { text: "Not sure? Start from a file" }), drop, status));
  host.append(el("p", { class: "small" }, "Results are kept in this browser until you ",
    el("button", { class: "link", type: "button", text: "start over", onclick: async () => { await forget(); ctx.rerender(); } }), "."));
}
