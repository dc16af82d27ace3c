// The robot link (issue 24, docs/robot.md): bring the robot's files home, record a run with an always-visible
// Stop, send gains to the robot. Registers its own task and steps (docs/ui.md, "The page's code").
import { el } from "../dom.js";
import { getJson, post, send } from "../api.js";
import { number, quantity } from "../format.js";
import { save, state, task as taskState } from "../store.js";
import { registerStep, registerTask } from "../tasks.js";
import { addFiles } from "./fit.js";
import { fieldWords, targetLabel } from "../words.js";

registerTask({
  key: "robot",
  title: "Connect to the robot",
  short: "Robot",
  needs: "The robot's Wi-Fi: bring back its logs, record a run through FTC Dashboard, send gains to it and check them.",
  steps: [["robot-pull", "Bring the robot's files"], ["robot-record", "Record a run"], ["robot-push", "Send and check"]],
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
    const notPulled = el("div", {});
    const button = el("button", { class: "primary", type: "button", text: "Connect to the robot" });
    button.addEventListener("click", async () => {
      status.textContent = "downloading…"; list.replaceChildren(); notPulled.replaceChildren(); button.disabled = true;
      try {
        const answer = await post("api/robot/pull", form());
        const files = [];
        for (const f of answer.files) files.push(new File([await (await send(f.url)).blob()], f.name));
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
        const failed = answer.not_pulled || [];
        status.textContent = (files.length ? `${files.length} file${files.length > 1 ? "s" : ""} brought back.` : "The robot has no files to bring back yet.")
          + (failed.length ? ` ${failed.length} could not be brought back (below).` : "");
        for (const line of answer.missing) list.append(el("li", { class: "small", text: line }));
        // each file the pull could not bring: which, why and what to do, in words (motorlab robot pull's exit 3)
        if (failed.length) notPulled.append(el("section", { class: "card not-pulled", role: "alert" },
          el("h3", { text: `Not brought back (${failed.length})` }),
          el("ul", {}, failed.map((n) => el("li", {}, el("strong", { text: n.file }), `: ${n.reason}. What to do: ${n.todo}.`)))));
        for (const key of tasks) host.append(el("p", {}, el("a", { class: "button", href: `#/${key}/fit`, text: `Open them in “${key}”` })));
      } catch (e) { status.textContent = ""; status.append(el("span", { class: "error", role: "alert", text: e.message })); }
      button.disabled = false;
    });
    host.append(el("p", {}, button), status, list, notPulled);
  },
});

let poller = null;
const stopPolling = () => { if (poller) { clearInterval(poller); poller = null; } };

// The red Stop bar: in view on every step that can start an OpMode, whether or not one runs (sticky at the
// bottom of the window), one element never rebuilt under the pointer. Stop sends STOP_OP_MODE at once: through
// the app's recording, or straight to the robot when the app runs none (an OpMode started elsewhere).
const IDLE = " Nothing runs on the robot from this page now. The Driver Station's STOP always works too.";
function stopBar() {
  const said = el("span", { text: IDLE });
  const stop = async () => {
    try { await post("api/robot/record/stop", form()); } catch (e) { said.replaceChildren(el("strong", { class: "error", role: "alert", text: ` ${e.message}` })); }
  };
  const bar = el("div", { class: "stop-bar", role: "region", "aria-label": "Stop the robot" },
    el("button", { class: "stop", type: "button", text: "Stop the robot", onclick: stop }), said);
  bar.running = (name) => { said.textContent = name ? ` ${name} runs on the robot. The Driver Station's STOP always works too.` : IDLE; };
  return bar;
}

// Follow the app's recording five times a second until it stops (also one started before this step was shown).
function watch({ live, bar, status, onStopped }) {
  stopPolling();
  const tick = async () => {
    const s = await getJson("api/robot/record");
    // the robot's last value of each key: a count as it is, another number to 4 significant digits (its telemetry
    // sends 22.721094103127637)
    const last = (k) => { const v = s.series[k] && s.series[k].length ? s.series[k][s.series[k].length - 1] : "";
      const n = typeof v === "string" && v.trim() !== "" ? Number(v) : v;
      return typeof n === "number" && Number.isFinite(n) && !Number.isInteger(n) ? number(n) : v; };
    live.textContent = s.state === "idle" ? "" : `${s.opmode}: ${s.state}, ${s.rows} packets\n` + (s.keys || []).map((k) => `${k} = ${last(k)}`).join("\n");
    if (s.state === "stopped" || s.state === "idle") { stopPolling(); bar.running(""); if (s.state === "stopped") await onStopped(s); } else bar.running(s.opmode);
  };
  poller = setInterval(() => tick().catch((e) => { status.textContent = e.message; }), 200);
}

// Start `opmode` (the person confirmed just before), then follow it.
async function startRun(fields, view) {
  await post("api/robot/record/start", form(fields));
  view.bar.running(fields.opmode);  // from the first moment, before the first status arrives
  watch(view);
}

// Shown again while an OpMode started from this page runs (the person left the step and came back).
async function resume(view) {
  const s = await getJson("api/robot/record");
  if (s.state !== "idle" && s.state !== "stopped") watch(view);
}

const explain = (after, s) => {
  after.replaceChildren(el("p", { text: `Stopped: ${s.stop_reason}.` }));
  if (s.still_running) after.append(el("p", { class: "error", role: "alert", text: "The OpMode may still be running: press STOP on the Driver Station." }));
  if (s.error) after.append(el("p", { class: "error", role: "alert", text: s.error }));
};

// Fit a recorded ramp with motorlab's feedforward analysis (the app's own API: the CLI's answer); kept for "Send".
async function fitRun(blob, cpr) {
  const f = new FormData();
  f.append("file", new File([blob], "run.csv"));
  if (cpr) f.append("cpr", cpr);
  const fit = await post("api/analyze/feedforward", f);
  const recorded = new Date().toLocaleTimeString([], { hour: "2-digit", minute: "2-digit" });
  state.shared.robotFit = { json: JSON.stringify(fit), from: `the run recorded at ${recorded}`, cpr };
  save();
  return fit;
}

const fitWords = (fit) => ["kS", "kV", "kA"].filter((k) => fit.parameters[k])
  .map((k) => `${k} = ${quantity(fit.parameters[k].value, fit.parameters[k].stderr, fit.parameters[k].unit)}`).join(", ");

registerStep("robot-record", {
  leave: stopPolling,
  render(host, ctx) {
    host.append(el("h2", { text: "Record a run" }),
      el("p", { text: "Choose an OpMode: motorlab starts it on the robot through FTC Dashboard when you press Start, records its telemetry with the battery voltage, and stops it after the time you give, when you press Stop, or when the connection drops. To tune a drive, record a ramp (motorlab's quasistatic ramp or Road Runner's ForwardRampLogger) and fit it here." }),
      robotFields());
    const status = el("p", { class: "status", role: "status" });
    const select = el("select", { id: "robot-opmode" });
    const seconds = el("input", { id: "robot-seconds", value: "20", inputmode: "decimal" });
    // the robot's encoder is the robot task's setting, never another task's (store.js: settings per task)
    const cpr = el("input", { id: "robot-cpr", value: taskState("robot").settings.cpr || "", inputmode: "decimal", onchange: (e) => { taskState("robot").settings.cpr = e.target.value.trim(); save(); } });
    const live = el("pre", { class: "live", "aria-live": "polite", style: "white-space:pre-wrap;overflow-wrap:anywhere" });
    const bar = stopBar();
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
    const stopped = async (s) => {
      explain(after, s);
      if (!s.log || s.check) return;
      const fitted = el("div", { role: "status" });
      after.append(el("p", {},
        el("button", { class: "primary", type: "button", text: "Fit this run", onclick: async () => {
          fitted.textContent = "fitting…";
          try {
            const fit = await fitRun(await (await send(s.log)).blob(), cpr.value.trim());
            fitted.replaceChildren(el("p", { text: `The fit: ${fitWords(fit)}.` }),
              el("button", { class: "primary", type: "button", text: "Send these gains to the robot", onclick: () => ctx.go("robot-push") }));
          } catch (e) { fitted.replaceChildren(el("p", { class: "error", role: "alert", text: e.message })); }
        } }), " ",
        el("button", { type: "button", text: "Open it in the mechanism task", onclick: async () => {
          const file = new File([await (await send(s.log)).blob()], "run.csv");
          await addFiles(taskState("mechanism"), [file]); ctx.goTask("mechanism", "fit");
        } })), fitted);
    };
    const start = el("button", { class: "primary", type: "button", text: "Start the OpMode on the robot" });
    start.addEventListener("click", async () => {
      if (!select.value) { status.textContent = "List the robot's OpModes and choose one first."; return; }
      if (!window.confirm(`Start “${select.value}” on the robot now? Keep clear of it.`)) return;
      after.replaceChildren();
      try { await startRun({ opmode: select.value, seconds: seconds.value, cpr: cpr.value }, { live, bar, status, onStopped: stopped }); } catch (e) { status.textContent = e.message; }
    });
    host.append(el("p", {}, load),
      el("div", { class: "fields" },
        el("div", { class: "field" }, el("label", { for: "robot-opmode", text: "OpMode" }), select),
        el("div", { class: "field" }, el("label", { for: "robot-seconds", text: "Stop after (s)" }), seconds),
        el("div", { class: "field" }, el("label", { for: "robot-cpr", text: fieldWords("cpr") }), cpr)),
      el("p", {}, start), status, live, after, bar);
    resume({ live, bar, status, onStopped: stopped }).catch(() => {});
  },
});

// One verification run: target and measured velocity against time (Plotly), its RMS error in words above.
function checkFigure(label, c) {
  const div = el("div", { class: "plot-area" });
  const figure = el("figure", { class: "plot", style: "min-width:0;margin:0" }, el("figcaption", { text: `${label}: RMS tracking error ${c.rms.toPrecision(3)} ${c.unit}` }), div);
  const layout = { height: 300, margin: { t: 16, r: 12, b: 44, l: 58 }, font: { size: 12, family: "system-ui, sans-serif" },
    legend: { orientation: "h", y: -0.3 }, xaxis: { title: { text: "time in s" } }, yaxis: { title: { text: `velocity in ${c.unit}` } } };
  const traces = [{ x: c.time, y: c.target, name: "target (vref)", mode: "lines", line: { dash: "dash", width: 3 } }, { x: c.time, y: c.measured, name: "measured", mode: "lines" }];
  // drawn once in the page (a figure drawn detached takes Plotly's default 700 px width and overflows a phone)
  const draw = (tries = 0) => {
    if (!div.isConnected && tries < 40) { setTimeout(() => draw(tries + 1), 25); return; }
    if (window.Plotly && div.isConnected) window.Plotly.react(div, traces, layout, { responsive: true, displaylogo: false });
  };
  return [figure, draw];
}

async function showChecks(host) {
  const checks = await getJson("api/robot/checks");
  const figures = [["Before", checks.before], ["After", checks.after]].filter(([, c]) => c).map(([label, c]) => checkFigure(label, c));
  host.replaceChildren();
  if (!figures.length) return;
  host.append(el("h3", { text: "Before and after" }), el("p", { role: "status", class: "check-words", text: checks.words }),
    el("div", { style: "display:grid;grid-template-columns:repeat(auto-fit,minmax(min(100%,320px),1fr));gap:.8em" }, ...figures.map(([f]) => f)));
  for (const [, draw] of figures) draw();
}

registerStep("robot-push", {
  leave: stopPolling,
  render(host, ctx) {
    host.append(el("h2", { text: "Send and check" }),
      el("p", { text: "motorlab reads the robot's @Config fields through FTC Dashboard, shows the values there and the new ones side by side, and writes only those after you confirm. They last until the robot controller app restarts: paste the code shown for good. Check the drive before and after writing: Road Runner's ManualFeedforwardTuner drives the robot forwards and backwards along 64 inches with the gains on the robot, and the app compares how closely it followed the target velocity each time." }),
      robotFields());
    const kept = state.shared.robotFit;
    const fit = el("input", { type: "file", id: "robot-fit", accept: ".json" });
    const target = el("select", { id: "robot-target" }, ...["roadrunner", "pedro", "ftc-pidf"].map((t) => el("option", { value: t, text: targetLabel(t) })));
    const cpr = el("input", { id: "robot-push-cpr", value: (kept && kept.cpr) || taskState("robot").settings.cpr || "", inputmode: "decimal" });
    const radius = el("input", { id: "robot-radius", value: taskState("robot").settings["wheel-radius"] || "" });
    const out = el("div", {});
    const fields = () => {
      const f = form({ target: target.value, cpr: cpr.value, "wheel-radius": radius.value });
      if (fit.files[0]) f.append("params", fit.files[0], fit.files[0].name);
      else if (kept) f.append("params", new File([kept.json], "fit.json"));
      return f;
    };
    const fail = (e) => out.append(el("p", { class: "error", role: "alert", text: e.message }));
    const bar = stopBar();
    const live = el("pre", { class: "live", "aria-live": "polite", style: "white-space:pre-wrap;overflow-wrap:anywhere" });
    const status = el("p", { class: "status", role: "status" });
    const compare = el("div", {});
    const opmode = el("input", { id: "robot-check-opmode", value: "ManualFeedforwardTuner" });
    const seconds = el("input", { id: "robot-check-seconds", value: "8", inputmode: "decimal" });
    const checked = async (s) => {
      if (s.error) status.replaceChildren(el("span", { class: "error", role: "alert", text: s.error }));
      else if (s.check) status.textContent = `The check ${s.check} writing is done (${s.stop_reason}).`;
      await showChecks(compare);
    };
    const check = (label) => async () => {
      if (!window.confirm(`Start “${opmode.value}” on the robot now (the check ${label} writing)? It drives the robot forwards and backwards along 64 inches, over and over, for ${seconds.value} s or until you press Stop. Keep 2 m clear in front of and behind it.`)) return;
      status.textContent = "";
      try { await startRun({ opmode: opmode.value, seconds: seconds.value, check: label }, { live, bar, status, onStopped: checked }); } catch (e) { status.textContent = e.message; }
    };
    const show = el("button", { class: "primary", type: "button", text: "Show old and new values", onclick: async () => {
      try {
        const plan = await post("api/robot/push/plan", fields());
        // for people: the new value rounded to its uncertainty (from the fit) with its unit; the value on the robot
        // has no uncertainty of its own (4 significant digits). What is written is the full value.
        const shown = (c, v, stderr) => (typeof v === "number" ? quantity(v, stderr, c.unit) : String(v));
        const rows = plan.changes.map((c) => el("tr", {}, el("td", { text: c.path }), el("td", { class: "num", text: shown(c, c.old, null) }), el("td", { class: "num", text: shown(c, c.new, c.stderr) })));
        const write = el("button", { class: "primary", type: "button", text: "Write these values to the robot", onclick: async () => {
          const f = fields(); f.append("confirm", "yes");
          if (plan.running) {
            if (!window.confirm(`${plan.running} is running on the robot. Write anyway?`)) return;
            f.append("while-running", "yes");
          }
          try {
            await post("api/robot/push/apply", f);
            out.append(el("p", { role: "status", text: `Written, read back and checked. ${plan.lifetime.charAt(0).toUpperCase()}${plan.lifetime.slice(1)}.` }), el("details", {}, el("summary", { text: "The code to paste into your robot code" }), el("pre", { style: "overflow-x:auto" }, el("code", { text: plan.snippet }))),
              el("p", { text: `The old values are kept: ${plan.changes.map((c) => `${c.path.split(".").pop()} ${shown(c, c.old, null)}`).join(", ")}.` }),
              el("button", { type: "button", text: "Put the old values back", onclick: async () => {
                try { await post("api/robot/push/restore", form()); out.append(el("p", { role: "status", text: "The old values are back on the robot." })); } catch (e) { fail(e); }
              } }));
          } catch (e) { fail(e); }
        } });
        out.replaceChildren(el("table", {}, el("thead", {}, el("tr", {}, el("th", { text: "Field" }), el("th", { text: "On the robot now" }), el("th", { text: "New" }))), el("tbody", {}, rows)),
          plan.running ? el("p", { class: "error", text: `${plan.running} is running on the robot.` }) : "", el("p", {}, write));
      } catch (e) { out.replaceChildren(); fail(e); }
    } });
    host.append(
      kept ? el("p", { text: `The fit of ${kept.from} is used, unless you choose another file below.` }) : "",
      el("div", { class: "fields" },
        el("div", { class: "field" }, el("label", { for: "robot-fit", text: kept ? "Another fit (a motorlab result file, .json)" : "The fit (a motorlab result file, .json)" }), fit),
        el("div", { class: "field" }, el("label", { for: "robot-target", text: "Whose fields" }), target),
        el("div", { class: "field" }, el("label", { for: "robot-push-cpr", text: fieldWords("cpr") }), cpr),
        el("div", { class: "field" }, el("label", { for: "robot-radius", text: "Wheel radius (Pedro)" }), radius)),
      el("h3", { text: "Check the drive" }),
      el("div", { class: "fields" },
        el("div", { class: "field" }, el("label", { for: "robot-check-opmode", text: "Check OpMode" }), opmode, el("small", { text: "Road Runner's ManualFeedforwardTuner: it publishes the target and measured velocity" })),
        el("div", { class: "field" }, el("label", { for: "robot-check-seconds", text: "Each check runs for (s)" }), seconds)),
      el("p", {}, el("button", { type: "button", text: "Check before writing", onclick: check("before") }), " ", show),
      out,
      el("p", {}, el("button", { type: "button", text: "Check after writing", onclick: check("after") })),
      status, live, compare, bar);
    showChecks(compare).catch(() => {});
    resume({ live, bar, status, onStopped: checked }).catch(() => {});
  },
});
