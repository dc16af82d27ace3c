// The tasks the first screen offers, each a short sequence of steps. A later module (e.g. the robot link)
// adds its own task or step with registerTask() / registerStep() before the page starts: see docs/ui.md.
// A task's words (title, short, needs) come from /api/schema's "tasks" (motorlab.glossary.TASKS; words.js).
export const TASKS = [];
export const STEPS = {};

export function registerTask(task) { TASKS.push(task); }
export function registerStep(key, module) { STEPS[key] = module; }
export const findTask = (key) => TASKS.find((t) => t.key === key);

registerTask({
  key: "drive",
  steps: [["fit", "Your files and the fit"], ["gains", "Gains for your code"]],
  targets: ["roadrunner", "pedro"],
  target: () => "roadrunner",
});

registerTask({
  key: "mechanism",
  steps: [["fit", "Your files and the fit"], ["gains", "Gains for your code"]],
  targets: ["ftc-pidf", "ftc-power", "wpilib", "volts"],
  target: (t) => ((t.files || []).some((f) => f.info && /sysid|wpilog|frc-char/.test(f.info.format || "")) ? "wpilib" : "ftc-pidf"),
});

registerTask({
  key: "bench",
  steps: [["session", "Your session and its report"], ["fit", "Dynamometer runs"], ["gains", "Gains for your code"]],
  targets: ["ftc-pidf", "ftc-power", "wpilib", "volts"],
  target: () => "ftc-pidf",
});

registerTask({
  key: "expert",
  steps: [["fit", "Your files and the fit"], ["gains", "Gains for your code"]],
  targets: [],
  target: () => "volts",
});
