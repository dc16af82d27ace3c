// Numbers for people: human-scaled units, the uncertainty in the same unit, "not determined" in words.
const PREFIXES = [[1e9, "G"], [1e6, "M"], [1e3, "k"], [1, ""], [1e-3, "m"], [1e-6, "µ"], [1e-9, "n"]];
// Units whose leading symbol takes an SI prefix (the rest of the unit is kept as is).
const PREFIXABLE = /^(H|ohm|Ω|V|A|W|Hz|F|s|m|N\*m)$/;  // simple units only: "mV·s/rad" reads worse than 0.0123 V·s/rad
const SUPERSCRIPT = { "-": "⁻", "0": "⁰", "1": "¹", "2": "²", "3": "³", "4": "⁴", "5": "⁵", "6": "⁶", "7": "⁷", "8": "⁸", "9": "⁹" };

// The FTC motor controller's output (32767 = full power), which the server's units call "hub".
const CONTROLLER_OUTPUT = "output";

export function prettyUnit(unit) {
  if (!unit || unit === "1") return "";
  return String(unit).replace(/\bhub\b/g, CONTROLLER_OUTPUT).replace(/^1\/([A-Za-z]+)$/, "$1^-1").replace(/\bohm\b/g, "Ω").replace(/\*/g, "·").replace(/\^(-?\d+)/g, (_, p) => [...p].map((c) => SUPERSCRIPT[c]).join(""))
    .replace(/\bdeg\b/g, "°");
}

// x to `digits` significant digits; `zeros`: trailing zeros kept (0.67500 says five digits are known, 0.675 three).
function sig(x, digits, zeros = false) {
  if (x === 0) return "0";
  const s = Number(x.toPrecision(digits));
  const abs = Math.abs(s);
  if (abs >= 1e-3 && abs < 1e6) return zeros ? s.toPrecision(digits) : String(s);
  const [m, e] = s.toExponential(digits - 1).split("e");
  return `${zeros ? m : Number(m)} × 10${[...String(Number(e))].map((c) => SUPERSCRIPT[c]).join("")}`;
}

// The scale (power of 1000) that puts |x| in [1, 1000) for a prefixable unit.
function prefixFor(x, unit) {
  const m = PREFIXABLE.exec(unit || "");
  if (!m || !Number.isFinite(x) || x === 0) return [1, ""];
  if (m[1] === "s" && Math.abs(x) >= 1) return [1, ""];  // 12.8 s, not 12.8 ks for long times
  if (m[1] === "g") return [1, ""];
  for (const [f, p] of PREFIXES) if (Math.abs(x) >= f * 0.9995) return [f, p];
  return PREFIXES[PREFIXES.length - 1];
}

function withPrefix(prefix, unit) {
  if (!prefix) return prettyUnit(unit);
  const u = String(unit).replace(/^ohm/, "Ω");
  return prettyUnit(prefix + u);
}

// Relative uncertainty below which a value is shown to 5 significant digits (no false precision).
const FINEST = 1e-4;

// "690 ± 10 µH"; value null -> "not determined".
export function quantity(value, stderr, unit) {
  if (value === null || value === undefined || (typeof value === "number" && !Number.isFinite(value))) return "not determined";
  if (typeof value !== "number") return `${value} ${prettyUnit(unit)}`.trim();
  const [f, p] = prefixFor(value, unit);
  const u = withPrefix(p, unit || "");
  const v = value / f;
  if (stderr === null || stderr === undefined || !Number.isFinite(stderr) || stderr <= 0) return `${sig(v, 4)} ${u}`.trim();
  const e = stderr / f;
  // an uncertainty below 0.01 % is the file's rounding or the model's, not the measurement's: no digits for it
  if (v !== 0 && e / Math.abs(v) < FINEST) return `${sig(v, 5, true)} ${u} (uncertainty below 0.01 %)`.replace(/\s+\(/, " (");
  // the uncertainty to 2 significant digits, the value to the same decimal place
  const place = Math.floor(Math.log10(e)) - 1;
  const dec = Math.max(0, -place);
  // fixed decimals while they stay readable (0.125318 ± 0.000015), else one power of ten for both:
  // (9.612 ± 0.012) × 10⁻⁵
  const fixed = place >= -7 && Math.abs(v) < 1e6 && (Math.abs(v) >= 1e-4 || v === 0);
  if (!fixed) {
    const p10 = Math.floor(Math.log10(Math.abs(v) || e));
    const [sv, se] = [v / 10 ** p10, e / 10 ** p10];
    const pl = Math.floor(Math.log10(se)) - 1, d = Math.max(0, -pl);
    const r = (x) => (Math.round(x / 10 ** pl) * 10 ** pl).toFixed(d);
    return `(${r(sv)} ± ${r(se)}) × 10${[...String(p10)].map((c) => SUPERSCRIPT[c]).join("")} ${u}`.trim();
  }
  const round = (x) => (Math.round(x / 10 ** place) * 10 ** place).toFixed(dec);
  return `${round(v)} ± ${round(e)} ${u}`.trim();
}

export function number(value, digits = 4) {
  if (value === null || value === undefined || (typeof value === "number" && !Number.isFinite(value))) return "not determined";
  return typeof value === "number" ? sig(value, digits) : String(value);
}

// A time in seconds for people: "56 ms", "12.8 s".
export function duration(seconds) {
  if (seconds === null || seconds === undefined) return "not reached";
  return quantity(seconds, null, "s");
}

// An overshoot in percent for people: "no overshoot" below what a plot or a robot shows (0.1 %).
export function overshoot(percent) {
  if (percent === null || percent === undefined || !Number.isFinite(percent) || percent < 0.1) return "no overshoot";
  return `${number(percent, 2)} %`;
}

// R² for people: four decimals, "above 0.9999" where they would round to 1 (a fit is never exactly perfect).
export function share(r2) {
  if (typeof r2 !== "number" || !Number.isFinite(r2)) return "not determined";
  return r2 >= 0.99995 ? "above 0.9999" : r2.toFixed(4).replace("-", "−");
}

// A correlation for people: two decimals with a true minus sign (−1.00, not -1).
export function correlation(c) {
  return c.toFixed(2).replace("-", "−");
}

// The error a simulated step leaves once settled, for people: "none" below 0.1 % of the step (the simulation's
// rounding, -4.568 × 10⁻⁶ rot/s after a 54 rot/s step, nothing a plot or a robot shows), else with its unit.
export function settledError(error, step, unit) {
  if (typeof error === "number" && Number.isFinite(error) && typeof step === "number" && step !== 0
      && Math.abs(error) < 1e-3 * Math.abs(step)) return "none (below 0.1 % of the step)";
  return quantity(error, null, unit);
}
