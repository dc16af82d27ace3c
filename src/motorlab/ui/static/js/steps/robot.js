// The robot link (issue 24, docs/robot.md): bring the robot's files home, record a run with an always-visible
// Stop, send gains to the robot. Registers its own task and steps (docs/ui.md, "The page's code").
import { el } from "../dom.js";
import { getJson, post } from "../api.js";
import { save, state, task as taskState } from "../store.js";
import { registerStep, registerTask } from "../tasks.js";
import { addFiles } from "./fit.js";
import { fieldWords } from "../words.js";

registerTask({
  key: "robot",
  title: "Connect to the robot",
  short: "Robot",
  needs: "The robot's Wi-Fi: bring back its logs, record a run through FTC Dashboard, send gains to it.",
  steps: [["robot-pull", "Bring the robot's files"], ["robot-record", "Record a run"], ["robot-push", "Send to the robot"]],
  targets: ["roadrunner", "pedro", "ftc-pidf"],
  target: () => "roadrunner",
});

function robotFields() {
  const r = (state.shared.robot = state.shared.robot || { host: "192.168.43.1", http: "8080", dashboard: "8000" });
  const input = (label, key, help) => {
    const id = `robot-${key}`;
    const field = el("input", { id, value: r[key], onchange: (e) => { r[key] = e.target.value.trim(); save(); } });
    return el("div", { class: "field" }, el("label", { for: id, text: label }), field, el("small", { text: help }));
  };
  return el("div", { class: "fields" },
    input("Robot address", "host", "Control Hub 192.168.43.1, phone 192.168.49.1: the only address contacted"),
    input("Web server port", "http", "8080 on a robot"),
    input("FTC Dashboard port", "dashboard", "8000 on a robot"));
}

const robot = () => state.shared.robot || { host: "192.168.43.1", http: "8080", dashboard: "8000" };

function form(extra) {
  const f = new FormData();
  const r = robot();
  f.append("host", r.host); f.append("http-port", r.http); f.append("dashboard-port", r.dashboard);
  for (const [k, v] of Object.entries(extra || {})) if (v !== undefined && v !== "") f.append(k, v);
  return f;
}

registerStep("robot-pull", {
  render(host, ctx) {
    host.append(el("h2", { text: "Bring the robot's files" }),
      el("p", { text: "Connect this computer to the robot's Wi-Fi. motorlab downloads Road Runner's tuning files, its FlightRecorder logs and motorlab's own OpMode logs, and proposes each one's analysis." }),
      robotFields());
    const status = el("p", { class: "status", role: "status" });
    const list = el("ul", { class: "files" });
    const button = el("button", { class: "primary", type: "button", text: "Connect to the robot" });
    button.addEventListener("click", async () => {
      status.textContent = "downloading…"; list.replaceChildren(); button.disabled = true;
      try {
        const answer = await post("api/robot/pull", form());
        const files = [];
        for (const f of answer.files) files.push(new File([await (await fetch(f.url)).blob()], f.name));
        const scratch = { files: [], options: {}, runs: {} };
        if (files.length) await addFiles(scratch, files);
        const tasks = new Set();
        for (const entry of scratch.files) {
          const key = (entry.info && entry.info.task) || "expert";
          taskState(key).files.push(entry); tasks.add(key);
          list.append(el("li", {}, el("strong", { text: entry.name }), ` — ${entry.info && entry.info.format_words ? entry.info.format_words : "not a log motorlab reads"}`,
            entry.info && entry.info.experiment ? `, proposed: ${entry.info.experiment}` : ""));
        }
        save();
        status.textContent = files.length ? `${files.length} file${files.length > 1 ? "s" : ""} brought back.` : "The robot has no files to bring back yet.";
        for (const line of answer.missing) list.append(el("li", { class: "small", text: line }));
        for (const key of tasks) host.append(el("p", {}, el("a", { class: "button", href: `#/${key}/fit`, text: `Open them in “${key}”` })));
      } catch (e) { status.textContent = ""; status.append(el("span", { class: "error", role: "alert", text: e.message })); }
      button.disabled = false;
    });
    host.append(el("p", {}, button), status, list);
  },
});

let poller = null;

function stopBar(onStop) {
  return el("div", { class: "stop-bar", role: "region", "aria-label": "Robot running" },
    el("button", { class: "stop", type: "button", text: "Stop the robot", onclick: onStop }),
    el("span", { text: " The OpMode runs on the robot. The Driver Station's STOP always works too." }));
}

registerStep("robot-record", {
  leave() { if (poller) { clearInterval(poller); poller = null; } },
  render(host, ctx) {
    host.append(el("h2", { text: "Record a run" }),
      el("p", { text: "Choose an OpMode: motorlab starts it on the robot through FTC Dashboard when you press Start, records its telemetry with the battery voltage, and stops it after the time you give, when you press Stop, or when the connection drops." }),
      robotFields());
    const status = el("p", { class: "status", role: "status" });
    const select = el("select", { id: "robot-opmode" });
    const seconds = el("input", { id: "robot-seconds", value: "20", inputmode: "decimal" });
    const cpr = el("input", { id: "robot-cpr", value: state.shared.cpr || "", inputmode: "decimal" });
    const live = el("pre", { class: "live", "aria-live": "polite" });
    const stop = async () => { await post("api/robot/record/stop", new FormData()); };
    const bar = stopBar(stop);  // one element, shown while the OpMode runs (never rebuilt under the pointer)
    bar.hidden = true;
    const after = el("div", {});
    const load = el("button", { type: "button", text: "List the robot's OpModes" });
    load.addEventListener("click", async () => {
      try {
        const r = robot();
        const answer = await getJson(`api/robot/opmodes?host=${encodeURIComponent(r.host)}&dashboard-port=${encodeURIComponent(r.dashboard)}`);
        select.replaceChildren(...answer.opmodes.map((m) => el("option", { value: m.name, text: `${m.name} (${m.group})` })));
        status.textContent = `${answer.opmodes.length} OpModes; battery ${answer.status.batteryVoltage} V.`;
      } catch (e) { status.textContent = e.message; }
    });
    const show = async () => {
      const s = await getJson("api/robot/record");
      const last = (k) => (s.series[k] && s.series[k].length ? s.series[k][s.series[k].length - 1] : "");
      live.textContent = s.state === "idle" ? "" : `${s.opmode}: ${s.state}, ${s.rows} packets\n` + (s.keys || []).map((k) => `${k} = ${last(k)}`).join("\n");
      bar.hidden = !(s.state === "running" || s.state === "init" || s.state === "connecting");
      if (s.state === "stopped") {
        clearInterval(poller); poller = null;
        after.replaceChildren(el("p", { text: `Stopped: ${s.stop_reason}.` }));
        if (s.still_running) after.append(el("p", { class: "error", role: "alert", text: "The OpMode may still be running: press STOP on the Driver Station." }));
        if (s.error) after.append(el("p", { class: "error", role: "alert", text: s.error }));
        if (s.log) after.append(el("button", { class: "primary", type: "button", text: "Fit this run", onclick: async () => {
          const file = new File([await (await fetch(s.log)).blob()], "run.csv");
          await addFiles(taskState("mechanism"), [file]); ctx.goTask("mechanism", "fit");
        } }));
      }
    };
    const start = el("button", { class: "primary", type: "button", text: "Start the OpMode on the robot" });
    start.addEventListener("click", async () => {
      if (!select.value) { status.textContent = "List the robot's OpModes and choose one first."; return; }
      if (!window.confirm(`Start “${select.value}” on the robot now? Keep clear of it.`)) return;
      try {
        await post("api/robot/record/start", form({ opmode: select.value, seconds: seconds.value, cpr: cpr.value }));
        after.replaceChildren();
        bar.hidden = false;  // Stop is there from the first moment, before the first status arrives
        poller = setInterval(() => show().catch((e) => { status.textContent = e.message; }), 200);
      } catch (e) { status.textContent = e.message; }
    });
    host.append(el("p", {}, load),
      el("div", { class: "fields" },
        el("div", { class: "field" }, el("label", { for: "robot-opmode", text: "OpMode" }), select),
        el("div", { class: "field" }, el("label", { for: "robot-seconds", text: "Stop after (s)" }), seconds),
        el("div", { class: "field" }, el("label", { for: "robot-cpr", text: fieldWords("cpr") }), cpr)),
      el("p", {}, start), bar, status, live, after);
    show().catch(() => {});
  },
});

registerStep("robot-push", {
  render(host, ctx) {
    host.append(el("h2", { text: "Send to the robot" }),
      el("p", { text: "motorlab reads the robot's @Config fields through FTC Dashboard, shows the values there and the new ones side by side, and writes only those after you confirm. They last until the robot controller app restarts: paste the code shown for good." }),
      robotFields());
    const fit = el("input", { type: "file", id: "robot-fit", accept: ".json" });
    const target = el("select", { id: "robot-target" }, ...["roadrunner", "pedro", "ftc-pidf"].map((t) => el("option", { value: t, text: t })));
    const cpr = el("input", { id: "robot-push-cpr", value: state.shared.cpr || "", inputmode: "decimal" });
    const radius = el("input", { id: "robot-radius", value: state.shared["wheel-radius"] || "" });
    const out = el("div", {});
    const fields = () => {
      const f = form({ target: target.value, cpr: cpr.value, "wheel-radius": radius.value });
      if (fit.files[0]) f.append("params", fit.files[0], fit.files[0].name);
      return f;
    };
    const fail = (e) => out.replaceChildren(el("p", { class: "error", role: "alert", text: e.message }));
    const show = el("button", { class: "primary", type: "button", text: "Show old and new values", onclick: async () => {
      try {
        const plan = await post("api/robot/push/plan", fields());
        const rows = plan.changes.map((c) => el("tr", {}, el("td", { text: c.path }), el("td", { text: String(c.old) }), el("td", { text: String(c.new) })));
        const write = el("button", { class: "primary", type: "button", text: "Write these values to the robot", onclick: async () => {
          const f = fields(); f.append("confirm", "yes");
          if (plan.running) {
            if (!window.confirm(`${plan.running} is running on the robot. Write anyway?`)) return;
            f.append("while-running", "yes");
          }
          try {
            await post("api/robot/push/apply", f);
            out.append(el("p", { role: "status", text: "Written, read back and checked. " + plan.lifetime }), el("pre", {}, el("code", { text: plan.snippet })),
              el("button", { type: "button", text: "Put the old values back", onclick: async () => {
                try { await post("api/robot/push/restore", form()); out.append(el("p", { role: "status", text: "The old values are back on the robot." })); } catch (e) { fail(e); }
              } }));
          } catch (e) { fail(e); }
        } });
        out.replaceChildren(el("table", {}, el("thead", {}, el("tr", {}, el("th", { text: "field" }), el("th", { text: "on the robot" }), el("th", { text: "new" }))), el("tbody", {}, rows)),
          plan.running ? el("p", { class: "error", text: `${plan.running} is running on the robot.` }) : "", write);
      } catch (e) { fail(e); }
    } });
    host.append(el("div", { class: "fields" },
      el("div", { class: "field" }, el("label", { for: "robot-fit", text: "The fit (a motorlab result file, .json)" }), fit),
      el("div", { class: "field" }, el("label", { for: "robot-target", text: "Whose fields" }), target),
      el("div", { class: "field" }, el("label", { for: "robot-push-cpr", text: fieldWords("cpr") }), cpr),
      el("div", { class: "field" }, el("label", { for: "robot-radius", text: "Wheel radius (Pedro)" }), radius)),
      el("p", {}, show), out);
  },
});
