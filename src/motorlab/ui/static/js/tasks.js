// The tasks the first screen offers, each a short sequence of steps. A later module (e.g. the robot link)
// adds its own task or step with registerTask() / registerStep() before the page starts: see docs/ui.md.
export const TASKS = [];
export const STEPS = {};

export function registerTask(task) { TASKS.push(task); }
export function registerStep(key, module) { STEPS[key] = module; }
export const findTask = (key) => TASKS.find((t) => t.key === key);

registerTask({
  key: "drive",
  title: "Tune a Road Runner or Pedro Pathing drive",
  short: "Drive",
  needs: "The files Road Runner's ramp loggers save (ForwardRampLogger …, .json) or its FlightRecorder logs (.log).",
  steps: [["fit", "Your files and the fit"], ["gains", "Gains for your code"]],
  targets: ["roadrunner", "pedro"],
  target: () => "roadrunner",
});

registerTask({
  key: "mechanism",
  title: "Tune a mechanism: flywheel, arm, elevator or drivetrain",
  short: "Mechanism",
  needs: "A WPILib SysId file (.json, .wpilog) or an FTC OpMode log (a spin-down), with an LCR table when you have one.",
  steps: [["fit", "Your files and the fit"], ["gains", "Gains for your code"]],
  targets: ["ftc-pidf", "ftc-power", "wpilib", "volts"],
  target: (t) => ((t.files || []).some((f) => f.info && /sysid|wpilog|frc-char/.test(f.info.format || "")) ? "wpilib" : "ftc-pidf"),
});

registerTask({
  key: "bench",
  title: "Characterise motors on a bench",
  short: "Bench",
  needs: "A session: its .toml file with its logs chosen together, its folder, or a .zip of the folder.",
  steps: [["session", "Your session and its report"], ["fit", "Dynamometer runs"], ["gains", "Gains for your code"]],
  targets: ["ftc-pidf", "ftc-power", "wpilib", "volts"],
  target: () => "ftc-pidf",
});

registerTask({
  key: "expert",
  title: "Analyse one experiment",
  short: "One experiment",
  needs: "For instructors and experts: any log of the seeds' experiments (LCR table, spin-down, torque, terminal speed …).",
  steps: [["fit", "Your files and the fit"], ["gains", "Gains for your code"]],
  targets: [],
  target: () => "volts",
});
