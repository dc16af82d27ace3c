// Words for what the schema names with symbols. /api/schema's own "label", "help", "unit", "parameters" and
// "targets" win; these are the fallbacks while a server without them answers.
const FIELD_WORDS = {
  cpr: "Encoder counts per revolution", "wheel-radius": "Wheel radius", "gear-ratio": "Gear ratio",
  frequency: "Test frequency", circuit: "Equivalent circuit shown by the meter", "outlier-z": "Outlier threshold (modified z-score)",
  "current-unit": "Unit of the current column", inertia: "Moment of inertia at the encoder shaft",
  "inertia-stderr": "Uncertainty of the moment of inertia", "disc-radius": "Flywheel disc radius",
  "disc-thickness": "Flywheel disc thickness", material: "Flywheel material", ratio: "Flywheel step-up ratio",
  cutoff: "Instant the power was cut", guard: "Time left out after the cut", arm: "Lever arm length",
  "arm-stderr": "Uncertainty of the lever arm", K: "Back-EMF constant of the motor", "K-stderr": "Uncertainty of the back-EMF constant",
  nominal: "Nominal amplifier gain", Ka: "Amplifier gain", I0: "Amplifier current at zero command", Km: "Torque constant",
  "Ka-stderr": "Uncertainty of the amplifier gain", "I0-stderr": "Uncertainty of the zero-command current",
  "Km-stderr": "Uncertainty of the torque constant", skip: "Time left out after each command edge", "tach-gain": "Tachometer gain",
  friction: "Friction model", R: "Winding resistance", "no-current": "Ignore the current column", mechanism: "Kind of mechanism (gravity)",
  side: "Drivetrain side", units: "Length unit", b: "Viscous friction", "b-stderr": "Uncertainty of the viscous friction",
  Tf: "Coulomb friction torque", "Tf-stderr": "Uncertainty of the Coulomb friction", spindown: "Spin-down log of the same rig",
  start: "Start of the constant-current phase", end: "End of the constant-current phase",
  "current-stderr": "Uncertainty of one current reading", "frequency-stderr": "Uncertainty of one frequency reading",
  "edges-per-rev": "Rising edges per revolution", current: "Constant current", loop: "What the loop controls",
  kv: "Velocity constant kV", ka: "Acceleration constant kA", ks: "Static friction voltage kS", params: "Results to design from",
  unit: "Which motor of the session", method: "Design method", qp: "Position error you accept", qv: "Velocity error you accept",
  r: "Voltage effort you accept", period: "Controller loop period", delay: "Measurement delay", "rise-time": "Rise time wanted",
  overshoot: "Largest overshoot wanted", target: "Your library", voltage: "Supply voltage", step: "Step size",
  session: "Session description", column: "Column meaning", emit: "Code language",
};

const CHOICE_WORDS = {
  velocity: "speed (velocity loop)", position: "position (position loop)", lqr: "LQR (as WPILib SysId)", poles: "pole placement",
  rad: "radians", rotations: "rotations", degrees: "degrees", ticks: "encoder ticks", m: "metres", simple: "none (flywheel, drivetrain)",
  elevator: "elevator (constant gravity)", arm: "arm (gravity × cos angle)", both: "both sides", left: "left side", right: "right side",
  series: "series", parallel: "parallel", steel: "steel", aluminium: "aluminium", auto: "automatic",
};

const PARAMETER_WORDS = {
  K: ["Back-EMF constant", "K"], R: ["Winding resistance", "R"], L: ["Winding inductance", "L"], J: ["Moment of inertia", "J"],
  b: ["Viscous friction", "b"], Tf: ["Coulomb friction torque", "Tf"], kS: ["Static friction voltage", "kS"],
  kV: ["Velocity constant", "kV"], kA: ["Acceleration constant", "kA"], kG: ["Gravity voltage", "kG"],
  Km: ["Torque constant", "Km"], Ka: ["Amplifier gain", "Ka"], I0: ["Current at zero command", "I0"],
  efficiency: ["Gearbox efficiency", "η"], eta: ["Gearbox efficiency", "η"], tach_gain: ["Tachometer gain", "kt"],
  gamma: ["Viscous decay rate", "γ = b/J"], Tf_over_J: ["Friction deceleration", "Tf/J"], b_over_J: ["Viscous decay rate", "b/J"],
  tau: ["Time constant", "τ"], tau_e: ["Electrical time constant", "τe"], tau_m: ["Mechanical time constant", "τm"],
  Q: ["Quality factor", "Q"], R_dc: ["DC resistance", "Rdc"], offset: ["Offset", ""], phi: ["Gravity angle offset", "φ"],
};

export const EXPERIMENT_WORDS = {
  lcr: "Winding resistance and inductance (LCR meter table)", spindown: "Spin-down: coasting after the power is cut",
  feedforward: "Feedforward fit: kS, kV, kA (SysId or Road Runner ramp)", identify: "Whole motor model from one transient log",
  torque: "Torque constant (lever arm on a scale)", amplifier: "Current amplifier gain", tachometer: "Tachometer gain",
  pulse: "Speed from encoder pulses at constant current", spinup: "Spin-up at constant current",
  terminal: "Terminal speed at several currents", "free-spinup": "Free spin-up from rest",
  curve: "Motor curve (dynamometer export or datasheet)",
};

const TARGET_WORDS = {
  roadrunner: "Road Runner 1.0", pedro: "Pedro Pathing", "ftc-pidf": "FTC PIDF (setVelocityPIDFCoefficients)",
  "ftc-power": "FTC motor power (setPower)", wpilib: "WPILib", volts: "Volts (any controller)",
  phoenix6: "CTRE Phoenix 6", phoenix5: "CTRE Phoenix 5", "spark-max": "REV SPARK MAX", "spark-flex": "REV SPARK Flex", rev: "REV SPARK MAX / Flex",
};

export const GAIN_WORDS = {
  kP: "Proportional gain kP", kI: "Integral gain kI", kD: "Derivative gain kD", kF: "Feedforward gain F", P: "Proportional gain P",
  I: "Integral gain I", D: "Derivative gain D", F: "Feedforward gain F", kS: "Static friction kS", kV: "Velocity feedforward kV",
  kA: "Acceleration feedforward kA", kG: "Gravity feedforward kG", axialGain: "Axial position gain", axialVelGain: "Axial velocity gain",
  lateralGain: "Lateral position gain", lateralVelGain: "Lateral velocity gain", headingGain: "Heading gain",
  headingVelGain: "Heading velocity gain", turnGain: "Turn gain", turnVelGain: "Turn velocity gain", inPerTick: "Inches per tick",
};

// Which measurement gives a parameter the gains need (the page offers it instead of a dead end).
export const MEASURED_BY = {
  K: "a spin-down log (or a free spin-up or terminal-speed run)", R: "an LCR meter table (or a terminal-speed run)",
  J: "a spin-down with the flywheel's inertia given (or a free spin-up)", kV: "a SysId file or a Road Runner ramp",
  kA: "a SysId file or a Road Runner ramp",
};

let SCHEMA = null;
export function setSchema(s) { SCHEMA = s; }

export function fieldLabel(f) { return f.label || FIELD_WORDS[f.name] || f.name.replace(/-/g, " ").replace(/^./, (c) => c.toUpperCase()); }
export function choiceLabel(name, value) {
  if (name === "target") return targetLabel(value);
  return CHOICE_WORDS[value] || String(value);
}
export function targetLabel(key) {
  const t = (SCHEMA && SCHEMA.targets || []).find((x) => x.key === key);
  return (t && t.label) || TARGET_WORDS[key] || key;
}
export function parameterWords(key) {
  const p = SCHEMA && SCHEMA.parameters && SCHEMA.parameters[key];
  if (p) return [p.name, p.symbol || key];
  if (PARAMETER_WORDS[key]) return PARAMETER_WORDS[key];
  return [key.replace(/_over_/g, " / ").replace(/_/g, " "), ""];
}

// One-line help: without "(default …)" (the box shows the default) and "[unit]" (shown beside it); flags in words.
export function helpWords(f) {
  const raw = f.help || "";
  return plain(raw.replace(/\s*\((?:default|e\.g\.)?[^()]*default[^()]*\)/gi, "").replace(/\s*\[[^\]]*\]/g, "")
    .replace(/\s*\(\d[^()]*\)\s*$/, "").replace(/\s+—\s*default.*$/, "").trim());
}

// Server text (errors, notes, help) with every "--option" named in words, so no flag shows outside a code box.
export function plain(text) {
  if (!text) return "";
  return String(text).replace(/(^|[^\w-])--([A-Za-z][\w-]*)/g, (m, pre, name) => `${pre}“${FIELD_WORDS[name] || name.replace(/-/g, " ")}”`);
}
